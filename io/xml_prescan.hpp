// What TinyXML 1 (2.6.2, urdfdom's XML parser) and tinyxml2 would build from XML text, as far as
// their cost goes, found in one linear pass each and without recursion:
//
//   depth       TinyXML 1 parses an element's children by calling itself, with no depth limit:
//               about 37,000 nested elements (120 KB of "<a>") overflow an 8 MB stack.
//   attributes  both parsers compare each new attribute with every earlier one of its element,
//               so one element of 200,000 attributes (2 MB) keeps them busy for minutes.
//
// A loader asks this scan before any parser sees the text and refuses text beyond its limits.
//
// The depth follows TinyXML 1's own tokenizer, not the XML specification, because the two
// disagree on text that matters here: TinyXML 1 ends "<?foo ...>" and "<!DOCTYPE ...>" at the
// first '>', lets "&#x...;" skip to the next ';', and in UTF-8 mode steps over a lead byte's
// whole sequence, so that "\xF0</a>" hides an end tag. Whether TinyXML 1 reads UTF-8 depends on
// a byte-order mark or on the first declaration; after a declaration both readings are scanned
// and the larger counts. Attributes are counted as TinyXML 1 and as tinyxml2 read them. Where a
// parser would stop at an error the scan may go on: it reports upper bounds.
// tests/fuzz/urdf_fuzz.cpp checks the depth against TinyXML 1 itself.
#pragma once

#include <string>
#include <string_view>

namespace io {

/// What a caller accepts.
struct XmlLimits {
  int depth = 0;       // deepest element nesting (a root element alone is 1)
  int attributes = 0;  // most attributes on one element
};

/// What prescan_xml() found: the first element beyond a limit, if any, and the largest values
/// seen before it.
struct XmlPrescan {
  enum class Excess { kNone, kDepth, kAttributes };
  Excess excess = Excess::kNone;
  int line = 0;        // line (from 1) of the element beyond a limit; 0 with kNone
  int depth = 0;       // deepest nesting TinyXML 1 reaches, at most limits.depth + 1
  int attributes = 0;  // most attributes on one element, at most limits.attributes + 1
};

/// Scans `text` (up to its first NUL byte, as both parsers read a C string) until the end or the
/// first element beyond `limits`.
XmlPrescan prescan_xml(std::string_view text, const XmlLimits& limits);

/// `text` as it is safe to hand to TinyXML 1: cut at its first NUL byte and followed by NUL bytes,
/// because TinyXML 1 steps up to four bytes past the end of unterminated text before it stops.
std::string tinyxml_input(std::string_view text);

}  // namespace io
