// Element nesting depth of XML text as TinyXML 1 (2.6.2, urdfdom's XML parser) would build it,
// found without recursion.
//
// TinyXML 1 parses an element's children by calling itself, with no depth limit: about 37,000
// nested elements (120 KB of "<a>") overflow an 8 MB stack. A loader that hands text to TinyXML 1
// asks this scan first and refuses text nested deeper than its limit.
//
// The scan follows TinyXML 1's own tokenizer, not the XML specification, because the two disagree
// on text that matters here: TinyXML 1 ends "<?foo ...>" and "<!DOCTYPE ...>" at the first '>',
// lets "&#x...;" skip to the next ';', and in UTF-8 mode steps over a lead byte's whole sequence,
// so that "\xF0</a>" hides an end tag. Whether TinyXML 1 reads UTF-8 depends on a byte-order mark
// or on the first declaration; after a declaration both readings are scanned and the deeper one
// counts. Where TinyXML 1 would stop at an error the scan may go on: it reports an upper bound.
// tests/fuzz/urdf_fuzz.cpp checks the bound against TinyXML 1 itself.
#pragma once

#include <string>
#include <string_view>

namespace io {

/// What tinyxml_nesting() found.
struct XmlNesting {
  int depth = 0;  // deepest element nesting (a root element alone is 1), at most limit + 1
  int line = 0;   // line (from 1) of the first element deeper than the limit; 0 when none is
};

/// Deepest element nesting TinyXML 1 can reach in `text` (read up to its first NUL byte, as
/// TinyXML 1 reads a C string). The scan stops at the first element deeper than `limit`.
XmlNesting tinyxml_nesting(std::string_view text, int limit);

/// `text` as it is safe to hand to TinyXML 1: cut at its first NUL byte and followed by NUL bytes,
/// because TinyXML 1 steps up to four bytes past the end of unterminated text before it stops.
std::string tinyxml_input(std::string_view text);

}  // namespace io
