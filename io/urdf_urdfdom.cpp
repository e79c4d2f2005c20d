#include "io/urdf_urdfdom.hpp"

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <atomic>
#include <cstdio>
#include <exception>
#include <mutex>
#include <unordered_set>

#include "io/urdf.hpp"
#include "io/xml_prescan.hpp"

namespace io::urdf_internal {

namespace {

// urdfdom reports through console_bridge, whose output handler is process-wide. Parses are
// therefore serialized by one mutex, and the handler object lives for the whole process because
// console_bridge keeps a pointer to it (as the "previous" handler) after we restore the caller's.
// This is the one piece of static mutable state in the loader; console_bridge's API forces it.

struct UrdfdomMessage {
  console_bridge::LogLevel level;
  std::string text;
};

class UrdfdomLog final : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    // console_bridge calls handlers under its own lock, so the sink is never written concurrently
    if (std::vector<UrdfdomMessage>* sink = sink_.load()) {
      sink->push_back({level, text});
    } else if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) {
      std::fprintf(stderr, "urdfdom: %s\n", text.c_str());  // reinstated by someone else
    }
  }
  std::atomic<std::vector<UrdfdomMessage>*> sink_{nullptr};
};

std::mutex& urdfdom_mutex() {
  static std::mutex m;
  return m;
}

UrdfdomLog& urdfdom_log() {
  static UrdfdomLog* const log = new UrdfdomLog;  // never destroyed, see above
  return *log;
}

// urdf::parseURDF with console_bridge output captured into `messages`
urdf::ModelInterfaceSharedPtr parse_with_urdfdom(const std::string& text,
                                                 std::vector<UrdfdomMessage>& messages) {
  const std::lock_guard<std::mutex> lock(urdfdom_mutex());
  UrdfdomLog& log = urdfdom_log();
  const console_bridge::LogLevel saved_level = console_bridge::getLogLevel();
  log.sink_.store(&messages);
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_WARN);
  console_bridge::useOutputHandler(&log);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(text);
  } catch (const std::exception& e) {
    messages.push_back({console_bridge::CONSOLE_BRIDGE_LOG_ERROR, e.what()});
    model.reset();
  }
  console_bridge::restorePreviousOutputHandler();
  console_bridge::setLogLevel(saved_level);
  log.sink_.store(nullptr);
  return model;
}

}  // namespace

std::string nesting_message(int line) {
  const std::string n = std::to_string(kMaxUrdfDepth);
  return (line > 0 ? "line " + std::to_string(line) + ": " : std::string()) +
         "elements are nested deeper than " + n + " (rule: a URDF nests XML elements at most " + n +
         " deep)";
}

std::optional<std::string> xml_rules_violation(const std::string& xml) {
  const XmlPrescan scan = prescan_xml(xml, {kMaxUrdfDepth, kMaxUrdfAttributes});
  switch (scan.excess) {
    case XmlPrescan::Excess::kNone:
      return std::nullopt;
    case XmlPrescan::Excess::kDepth:
      return nesting_message(scan.line);
    case XmlPrescan::Excess::kAttributes:
      break;
  }
  const std::string n = std::to_string(kMaxUrdfAttributes);
  return "line " + std::to_string(scan.line) + ": an element has more than " + n +
         " attributes (rule: an XML element of a URDF has at most " + n + " attributes)";
}

UrdfdomResult run_urdfdom(const std::string& xml) {
  UrdfdomResult out;
  if (std::optional<std::string> broken = xml_rules_violation(xml)) {
    out.errors.push_back(std::move(*broken));
    return out;
  }
  std::vector<UrdfdomMessage> messages;
  out.model = parse_with_urdfdom(tinyxml_input(xml), messages);
  std::unordered_set<std::string> seen;  // urdfdom repeats some warnings per shape list
  for (const UrdfdomMessage& m : messages) {
    if (m.level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      out.errors.push_back("urdfdom: " + m.text);
    } else if (m.level == console_bridge::CONSOLE_BRIDGE_LOG_WARN && seen.insert(m.text).second) {
      out.warnings.push_back("urdfdom: " + m.text);
    }
  }
  return out;
}

bool urdfdom_finds_a_robot(const std::string& xml) {
  if (xml_rules_violation(xml)) return false;
  TiXmlDocument doc;
  doc.Parse(tinyxml_input(xml).c_str());
  return !doc.Error() && doc.FirstChildElement("robot") != nullptr;
}

UrdfdomModelGuard::~UrdfdomModelGuard() {
  if (!model_) return;
  for (auto& [name, link] : model_->links_) {
    link->child_links.clear();
    link->child_joints.clear();
    link->parent_joint.reset();
  }
}

}  // namespace io::urdf_internal
