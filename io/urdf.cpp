#include "io/urdf.hpp"

#include <tinyxml2.h>

#include <filesystem>
#include <optional>
#include <system_error>

#include "io/read_file.hpp"
#include "io/urdf_import.hpp"
#include "io/urdf_scan.hpp"
#include "io/urdf_urdfdom.hpp"

// A URDF is read in three passes over its text, each in its own file:
//   1. urdf_urdfdom.cpp: the XML rules (kMaxUrdfDepth, kMaxUrdfAttributes) that bound the XML
//      parsers' work, checked before any of them runs;
//   2. tinyxml2, here, for well-formedness with a line number, and urdf_scan.cpp for what urdfdom
//      drops (warnings, capsules, repeated joint names, the tree);
//   3. urdfdom (urdf_urdfdom.cpp) on the document as tinyxml2 prints it back, so both see the
//      same names, then urdf_import.cpp for the Z-up to Y-up import into core::ModelBuilder.

namespace io {

using namespace core;  // io reads and writes core's types
using urdf_internal::fail;

namespace fs = std::filesystem;

Matrix3 urdf_to_y_up() {
  // rows: our x = URDF y (left), our y = URDF z (up), our z = URDF x (forward); det C = +1
  Matrix3 C;
  C << 0, 1, 0,  //
      0, 0, 1,   //
      1, 0, 0;
  return C;
}

namespace {

// Text that tinyxml2 refuses, or that has no <robot>: tinyxml2's message (with a line), and
// urdfdom's when its XML parser (TinyXML 1) finds no <robot> in the text either. Where TinyXML 1
// is more lenient, urdfdom would build links that tinyxml2 never saw (not checked for cycles),
// and on a rootless cycle it fails after building a shared_ptr cycle it never frees, so it is not
// asked then.
[[noreturn]] void refuse_document(const tinyxml2::XMLDocument& doc,
                                  const std::string& xml,
                                  const std::string& src) {
  if (doc.ErrorID() == tinyxml2::XML_ELEMENT_DEPTH_EXCEEDED) {
    // tinyxml2's own limit, deeper than ours: the text never reaches TinyXML 1
    fail(src, {urdf_internal::nesting_message(doc.ErrorLineNum())});
  }
  std::vector<std::string> lines;
  if (doc.Error()) {
    lines.push_back(std::string("not well-formed XML (rule: a URDF is an XML document): ") +
                    doc.ErrorStr());
  } else {
    lines.push_back("no <robot> element (rule: a URDF's root element is <robot>)");
  }
  if (!urdf_internal::urdfdom_finds_a_robot(xml)) {
    urdf_internal::UrdfdomResult urdfdom = urdf_internal::run_urdfdom(xml);
    const urdf_internal::UrdfdomModelGuard release_cycles(urdfdom.model);
    for (std::string& l : urdfdom.errors) lines.push_back(std::move(l));
  } else if (doc.Error()) {
    lines.push_back(
        "urdfdom's XML parser (TinyXML) accepts the text, but it is not "
        "well-formed XML");
  } else {
    lines.push_back(
        "urdfdom's XML parser (TinyXML) finds a <robot> element where tinyxml2 finds none");
  }
  fail(src, lines);
}

// The document as urdfdom reads it: printed back by tinyxml2, without declarations and a
// byte-order mark. Either would switch TinyXML 1 to UTF-8, where a stray lead byte swallows the
// characters after it; byte by byte TinyXML 1 sees the elements and names tinyxml2 saw.
std::string text_for_urdfdom(tinyxml2::XMLDocument& doc) {
  for (tinyxml2::XMLNode* node = doc.FirstChild(); node;) {
    tinyxml2::XMLNode* next = node->NextSibling();
    if (node->ToDeclaration()) doc.DeleteNode(node);
    node = next;
  }
  doc.SetBOM(false);
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return std::string(printer.CStr(), static_cast<size_t>(printer.CStrSize() - 1));
}

}  // namespace

LoadResult load_urdf_string(const std::string& xml,
                            const std::string& source_name,
                            const std::string& base_dir,
                            const LoadOptions& options) {
  const std::string& src = source_name;
  if (xml.size() > kMaxUrdfBytes) {
    fail(src, {"file is " + std::to_string(xml.size()) + " bytes (rule: a URDF is at most " +
               std::to_string(kMaxUrdfBytes) + " bytes)"});
  }
  // the one check of the XML rules, before any XML parser sees the text
  if (std::optional<std::string> broken = urdf_internal::xml_rules_violation(xml)) {
    fail(src, {*broken});
  }

  // well-formed XML first (tinyxml2 gives a line); urdfdom's own message goes with it
  tinyxml2::XMLDocument doc(true, tinyxml2::PRESERVE_WHITESPACE);
  doc.Parse(xml.data(), xml.size());
  tinyxml2::XMLElement* robot = doc.Error() ? nullptr : doc.FirstChildElement("robot");
  if (!robot) refuse_document(doc, xml, src);

  // what urdfdom drops: warnings, capsules, unsupported shapes (removed from the document)
  urdf_internal::Scan scan = urdf_internal::scan_document(robot);
  if (!scan.errors.empty()) fail(src, scan.errors);

  // urdfdom reads the document as tinyxml2 prints it back, so both see the same names (the
  // topology checks above hold for what urdfdom builds); any error it reports is fatal, since
  // it otherwise drops the element and goes on
  urdf_internal::UrdfdomResult urdfdom = urdf_internal::run_urdfdom(text_for_urdfdom(doc));
  const urdf_internal::UrdfdomModelGuard release_cycles(urdfdom.model);
  if (!urdfdom.model || !urdfdom.errors.empty()) {
    if (urdfdom.errors.empty()) urdfdom.errors.push_back("urdfdom rejected the file");
    urdfdom.errors.push_back(
        "urdfdom could not read the file completely (rule: the file must "
        "be valid URDF; nothing was loaded)");
    fail(src, urdfdom.errors);
  }

  std::vector<std::string> warnings = std::move(urdfdom.warnings);
  for (std::string& w : scan.warnings) warnings.push_back(std::move(w));
  return urdf_internal::import_urdf(*urdfdom.model, scan, src, base_dir, options,
                                    std::move(warnings));
}

LoadResult load_urdf_file(const std::string& path, const LoadOptions& options) {
  std::error_code ec;
  const fs::path p(path);
  // checked first: a FIFO or device would block the read, and these messages are the loader's
  if (!fs::is_regular_file(p, ec)) {
    fail(path, {fs::exists(p, ec) ? "is not a regular file" : "file not found"});
  }
  std::string xml;
  try {
    xml = read_file(path, kMaxUrdfBytes, "a URDF");
  } catch (const FileError& e) {
    throw ModelError({e.what()});  // "<path>: ..." with the cap when the file is too large
  }
  return load_urdf_string(xml, path, fs::absolute(p, ec).parent_path().string(), options);
}

}  // namespace io
