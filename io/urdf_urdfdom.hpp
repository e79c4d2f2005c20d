// The URDF loader's side of urdfdom and of TinyXML 1, the XML parser urdfdom uses (internal to
// io/urdf*.cpp): the XML rules that bound the XML parsers' work (kMaxUrdfDepth,
// kMaxUrdfAttributes), urdf::parseURDF with its console_bridge messages captured, and TinyXML 1's
// verdict on text tinyxml2 refused.
//
// Every call that hands text to TinyXML 1 checks the rules first and passes the text through
// tinyxml_input(), so no text beyond them reaches TinyXML 1.
#pragma once

#include <urdf_model/model.h>
#include <urdf_world/types.h>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace io::urdf_internal {

/// The XML rules, checked by prescan_xml(): nullopt when `xml` keeps them, else the first
/// violation, "line L: elements are nested deeper than N (rule: ...)" or "line L: an element has
/// more than N attributes (rule: ...)".
std::optional<std::string> xml_rules_violation(const std::string& xml);

/// The nesting message of xml_rules_violation(), for a refusal found by tinyxml2's own limit.
std::string nesting_message(int line);

/// What urdf::parseURDF made of a text.
struct UrdfdomResult {
  urdf::ModelInterfaceSharedPtr model;  // null when urdfdom refused the text
  std::vector<std::string> errors;      // "urdfdom: <message>" at error level
  std::vector<std::string> warnings;    // "urdfdom: <message>" at warning level, each once
};

/// urdf::parseURDF(xml) with console_bridge's output captured. Parses are serialized: urdfdom
/// reports through console_bridge's process-wide output handler. Text that breaks the XML rules
/// is not parsed; the violation is the one error.
UrdfdomResult run_urdfdom(const std::string& xml);

/// Whether urdfdom would read links from `xml`: TinyXML 1 (its XML parser) parses it without an
/// error and finds a <robot> element. False, unparsed, when it breaks the XML rules.
bool urdfdom_finds_a_robot(const std::string& xml);

/// Frees a urdfdom model's links even when they form a cycle: urdfdom links own their children
/// through shared_ptr, so a cyclic file makes a reference cycle that would never be freed.
class UrdfdomModelGuard {
 public:
  explicit UrdfdomModelGuard(urdf::ModelInterfaceSharedPtr model) : model_(std::move(model)) {}
  ~UrdfdomModelGuard();
  UrdfdomModelGuard(const UrdfdomModelGuard&) = delete;
  UrdfdomModelGuard& operator=(const UrdfdomModelGuard&) = delete;

 private:
  urdf::ModelInterfaceSharedPtr model_;
};

}  // namespace io::urdf_internal
