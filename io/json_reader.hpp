// The project's one way to read JSON input (character files, request files, dynamics states,
// sessions, wire messages): a bounded parse (io/json_parse.hpp), then typed access to fields in
// which every problem names the field and the rule broken.
//
//   const nlohmann::json doc = io::read_json_file(path, {.max_bytes = 16 << 20});
//   io::JsonFields f;                                  // stops at the first broken rule
//   const io::JsonField root(doc);                     // pointer ""
//   const double dt = f.number_or(root["dt"], 1.0 / 60, {.lo = 0, .hi = 1});
//   const int frames = static_cast<int>(f.integer(root["frames"], 0, 1000000));
//   // "/frames: 4294967297 is out of range (rule: an integer in [0, 1000000])"
//
// A JsonField is a value with its JSON pointer (RFC 6901), so a message names the field without
// string building at the call site. Messages read "<location>: <rule>", the location being the
// pointer after an optional base, spelled the way each format's users know it:
//   JsonStyle{}                                  /links/3/inertial/mass, "document root" for ""
//   JsonStyle{.base = "settings"}                settings/gains/drag
//   JsonStyle{.base = "pin", .dotted = true}     pin.link, pin.target.1
// Numbers are checked against their range, never wrapped or truncated.
//
// Two ways to report: JsonFields throws JsonFieldError at the first broken rule and returns
// values; JsonReader (OnError::kCollect) records every error and returns std::nullopt for a bad
// field, so one pass over a file reports all of its mistakes.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <limits>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "io/json_parse.hpp"

namespace io {

/// Hand-authored quaternions may be this far from unit length (norm); they are normalized.
constexpr double kQuaternionNormTolerance = 1e-3;
/// Below this norm a quaternion has no direction, whatever the tolerance.
constexpr double kMinQuaternionNorm = 1e-6;
/// "No cap" for array sizes.
constexpr std::size_t kAnySize = std::numeric_limits<std::size_t>::max();

/// A value of a document and its JSON pointer. A member or element that is not there is a field
/// with no value, so it can be named (as missing) before it is known to exist.
class JsonField {
 public:
  /// The whole document: pointer "". The field refers to `document`, which must outlive it.
  explicit JsonField(const nlohmann::json& document) : value_(&document) {}
  explicit JsonField(const nlohmann::json&& document) = delete;
  /// `value` (nullptr: absent) named by `pointer`.
  JsonField(const nlohmann::json* value, std::string pointer)
      : value_(value), pointer_(std::move(pointer)) {}

  /// Member `key`; absent unless this is an object that has it.
  JsonField operator[](std::string_view key) const;
  /// Element `index`; absent unless this is an array that long.
  JsonField operator[](std::size_t index) const;

  /// Present in the document (possibly null).
  bool exists() const { return value_ != nullptr; }
  explicit operator bool() const { return exists(); }
  /// Present and not null (a null member counts as left out).
  bool given() const;
  /// Elements of an array or members of an object; 0 otherwise.
  std::size_t size() const;

  const nlohmann::json& operator*() const { return *value_; }
  const nlohmann::json* operator->() const { return value_; }
  const std::string& pointer() const { return pointer_; }

 private:
  const nlohmann::json* value_ = nullptr;
  std::string pointer_;
};

/// Message wording. kDocument (file formats): "expected a number, got a string", "quaternion
/// [w, x, y, z] has norm 2". kRequest (requests and states): nlohmann's type names, "expected a
/// number, got string", "quaternion norm is 2". Each keeps the form its users know.
enum class JsonWording { kDocument, kRequest };

/// How a reader names fields in its messages.
struct JsonStyle {
  std::string base = "";               // prefix of every location (a message type, a section)
  bool dotted = false;                 // "base.a.0" instead of "base/a/0"
  std::string root = "document root";  // location of the whole document when base is empty
  JsonWording wording = JsonWording::kDocument;
};

/// Closed range [lo, hi]; the default admits every finite number.
struct NumberRange {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
};

/// A field that breaks a rule. what() is "<location>: <rule>".
class JsonFieldError : public std::runtime_error {
 public:
  JsonFieldError(std::string location, std::string pointer, std::string rule);
  std::string location;  // as the reader's style spells it
  std::string pointer;   // JSON pointer of the field
  std::string rule;
};

/// Typed access to fields. Every accessor checks one rule; a field that breaks it is reported
/// (thrown as JsonFieldError, or recorded under OnError::kCollect) and the accessor returns
/// std::nullopt (false for the shape checks). An absent field is reported as missing.
class JsonReader {
 public:
  enum class OnError { kThrow, kCollect };
  explicit JsonReader(JsonStyle style = {}, OnError on_error = OnError::kThrow);

  // --- reporting
  /// Reports that `field` breaks `rule`: throws (kThrow) or records it (kCollect).
  void fail(const JsonField& field, const std::string& rule);
  void fail_at(const std::string& pointer, const std::string& rule);
  /// Records a warning "<location>: <what>", or passes it to the sink when one is set.
  void warn(const JsonField& field, const std::string& what);
  void warn_at(const std::string& pointer, const std::string& what);
  /// Warnings go to `sink` as they are found instead of to warnings().
  void set_warning_sink(std::function<void(const std::string&)> sink);
  /// "<location>" of a pointer in this reader's style.
  std::string location(const std::string& pointer) const;
  /// The kind of a value for messages: "a string" or "string" (see JsonWording).
  std::string kind(const nlohmann::json& value) const;
  /// Recorded "<location>: <rule>" lines (kCollect) and warnings, in order.
  const std::vector<std::string>& errors() const { return errors_; }
  const std::vector<std::string>& warnings() const { return warnings_; }

  // --- presence and shape
  /// The field is present; else reports "missing (rule: required)".
  bool present(const JsonField& field);
  bool object(const JsonField& field);
  /// An array of at most `max_size` elements (`what` names them in the message).
  bool array(const JsonField& field, std::size_t max_size = kAnySize, std::string_view what = "");
  /// Warns "unknown key (ignored)" about every member of an object that is not in `known`.
  void warn_unknown_keys(const JsonField& object, std::initializer_list<std::string_view> known);
  /// Reports the first member of an object that is not in `known`, naming the known keys.
  bool refuse_unknown_keys(const JsonField& object, std::initializer_list<std::string_view> known);

  // --- values
  /// A finite number in `range`.
  std::optional<double> number(const JsonField& field, NumberRange range = {});
  /// An integer (no fraction, no exponent) in [lo, hi].
  std::optional<std::int64_t> integer(const JsonField& field, std::int64_t lo, std::int64_t hi);
  std::optional<bool> boolean(const JsonField& field);
  std::optional<std::string> string(const JsonField& field);
  /// An array of exactly `n` numbers, each in `range`.
  std::optional<Eigen::VectorXd> numbers(const JsonField& field, int n, NumberRange range = {});
  template <int N>
  std::optional<Eigen::Matrix<double, N, 1>> vector(const JsonField& field,
                                                    NumberRange range = {}) {
    auto v = numbers(field, N, range);
    if (!v) return std::nullopt;
    return Eigen::Matrix<double, N, 1>(*v);
  }
  /// A row-major 3×3 matrix: an array of three arrays of three numbers.
  std::optional<Eigen::Matrix3d> matrix(const JsonField& field);
  /// A quaternion [w, x, y, z] whose norm is within `tolerance` of 1 (and above
  /// kMinQuaternionNorm). A value already unit to rounding (|q|² within 1e-14 of 1) is kept bit
  /// for bit; any other is normalized.
  std::optional<Eigen::Quaterniond> quaternion(const JsonField& field,
                                               double tolerance = kQuaternionNormTolerance);

 private:
  // reports a type mismatch: "expected <what>, got <kind>"
  void expected(const JsonField& field, const std::string& what);

  JsonStyle style_;
  OnError on_error_;
  std::function<void(const std::string&)> warning_sink_;
  std::vector<std::string> errors_;
  std::vector<std::string> warnings_;
};

/// JsonReader that stops at the first broken rule (JsonFieldError) and returns plain values.
/// Accessors named *_or return `fallback` when the field is absent (a null is not absent).
class JsonFields {
 public:
  explicit JsonFields(JsonStyle style = {}) : reader_(std::move(style)) {}

  [[noreturn]] void fail(const JsonField& field, const std::string& rule);
  void warn(const JsonField& field, const std::string& what) { reader_.warn(field, what); }
  void set_warning_sink(std::function<void(const std::string&)> sink) {
    reader_.set_warning_sink(std::move(sink));
  }
  const std::vector<std::string>& warnings() const { return reader_.warnings(); }
  std::string kind(const nlohmann::json& value) const { return reader_.kind(value); }

  // shape checks return the field, so that `f.object(doc["settings"])["damping"]` reads on
  JsonField present(const JsonField& field);
  JsonField object(const JsonField& field);
  JsonField array(const JsonField& field,
                  std::size_t max_size = kAnySize,
                  std::string_view what = "");
  void warn_unknown_keys(const JsonField& object, std::initializer_list<std::string_view> known) {
    reader_.warn_unknown_keys(object, known);
  }
  void refuse_unknown_keys(const JsonField& object, std::initializer_list<std::string_view> known);

  double number(const JsonField& field, NumberRange range = {});
  double number_or(const JsonField& field, double fallback, NumberRange range = {});
  std::int64_t integer(const JsonField& field, std::int64_t lo, std::int64_t hi);
  std::int64_t integer_or(const JsonField& field,
                          std::int64_t fallback,
                          std::int64_t lo,
                          std::int64_t hi);
  bool boolean(const JsonField& field);
  bool boolean_or(const JsonField& field, bool fallback);
  std::string string(const JsonField& field);
  Eigen::VectorXd numbers(const JsonField& field, int n, NumberRange range = {});
  Eigen::Vector3d vector3(const JsonField& field, NumberRange range = {});
  Eigen::Quaterniond quaternion(const JsonField& field,
                                double tolerance = kQuaternionNormTolerance);

 private:
  JsonReader reader_;
};

/// Runs `read`, rethrowing JsonFieldError as `Error` with the same message, so that each layer
/// keeps its own exception type (cli::RequestError, animator::SessionError, ...).
template <typename Error, typename Read>
auto rethrow_as(Read&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const JsonFieldError& e) {
    throw Error(e.what());
  }
}

}  // namespace io
