// libFuzzer harness for io/urdf.hpp. Any input must load or fail with core::ModelError; nothing
// else may escape, crash, hang or leak. It also holds io/xml_prescan.hpp to its promise, against
// TinyXML 1 itself: when the scan finds the text within the loader's limits (so TinyXML 1 can
// parse it safely), TinyXML 1 builds no element deeper, and none with more attributes, than the
// scan reported.
#include <tinyxml.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "io/urdf.hpp"
#include "io/xml_prescan.hpp"

namespace {

// deepest element of a TinyXML 1 document (a root element is 1) and most attributes on one,
// walked without recursion
io::XmlPrescan tinyxml_shape(const TiXmlDocument& doc) {
  io::XmlPrescan out;
  int depth = 1;
  const TiXmlNode* node = doc.FirstChild();
  while (node) {
    if (const TiXmlElement* e = node->ToElement()) {
      out.depth = std::max(out.depth, depth);
      int attributes = 0;
      for (const TiXmlAttribute* a = e->FirstAttribute(); a; a = a->Next()) ++attributes;
      out.attributes = std::max(out.attributes, attributes);
    }
    if (node->FirstChild()) {
      node = node->FirstChild();
      ++depth;
      continue;
    }
    while (node && !node->NextSibling()) {
      node = node->Parent();
      --depth;
      if (node == &doc) node = nullptr;
    }
    if (node) node = node->NextSibling();
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const io::XmlPrescan scan = io::prescan_xml(text, {io::kMaxUrdfDepth, io::kMaxUrdfAttributes});
  if (scan.excess == io::XmlPrescan::Excess::kNone) {
    TiXmlDocument doc;
    doc.Parse(io::tinyxml_input(text).c_str());
    const io::XmlPrescan built = tinyxml_shape(doc);
    if (built.depth > scan.depth || built.attributes > scan.attributes) std::abort();
  }
  try {
    io::load_urdf_string(text, "fuzz.urdf", "");
  } catch (const core::ModelError&) {
  }
  return 0;
}
