#include "io/json_reader.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <utility>

namespace io {

namespace {

using Json = nlohmann::json;

// The token of a pointer segment with RFC 6901's escapes undone.
std::string unescaped(std::string_view token) {
  std::string out;
  for (std::size_t i = 0; i < token.size(); ++i) {
    if (token[i] == '~' && i + 1 < token.size() && (token[i + 1] == '0' || token[i + 1] == '1')) {
      out += token[i + 1] == '0' ? '~' : '/';
      ++i;
    } else {
      out += token[i];
    }
  }
  return out;
}

// "a.b.0" from "/a/b/0"
std::string dotted(const std::string& pointer) {
  std::string out;
  std::size_t start = 1;
  while (start <= pointer.size()) {
    const std::size_t end = std::min(pointer.find('/', start), pointer.size());
    if (!out.empty()) out += '.';
    out += unescaped(std::string_view(pointer).substr(start, end - start));
    start = end + 1;
  }
  return out;
}

std::string range_rule(const char* what, NumberRange r) {
  const bool has_lo = std::isfinite(r.lo), has_hi = std::isfinite(r.hi);
  if (has_lo && has_hi) {
    return std::string(what) + " in [" + message_number(r.lo) + ", " + message_number(r.hi) + "]";
  }
  if (has_lo) return std::string(what) + " >= " + message_number(r.lo);
  return std::string(what) + " <= " + message_number(r.hi);
}

std::string joined(std::initializer_list<std::string_view> words) {
  std::string out;
  for (std::string_view w : words) {
    if (!out.empty()) out += ", ";
    out += w;
  }
  return out;
}

bool known(std::initializer_list<std::string_view> keys, std::string_view key) {
  return std::find(keys.begin(), keys.end(), key) != keys.end();
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// JsonField

JsonField JsonField::operator[](std::string_view key) const {
  std::string pointer = json_pointer(pointer_, key);
  if (value_ == nullptr || !value_->is_object()) return JsonField(nullptr, std::move(pointer));
  const auto it = value_->find(key);
  return JsonField(it == value_->end() ? nullptr : &*it, std::move(pointer));
}

JsonField JsonField::operator[](std::size_t index) const {
  std::string pointer = json_pointer(pointer_, index);
  if (value_ == nullptr || !value_->is_array() || index >= value_->size()) {
    return JsonField(nullptr, std::move(pointer));
  }
  return JsonField(&(*value_)[index], std::move(pointer));
}

bool JsonField::given() const { return value_ != nullptr && !value_->is_null(); }

std::size_t JsonField::size() const {
  if (value_ == nullptr || !value_->is_structured()) return 0;
  return value_->size();
}

JsonFieldError::JsonFieldError(std::string location_, std::string pointer_, std::string rule_)
    : std::runtime_error(location_ + ": " + rule_),
      location(std::move(location_)),
      pointer(std::move(pointer_)),
      rule(std::move(rule_)) {}

// ---------------------------------------------------------------------------------------------
// JsonReader: reporting

JsonReader::JsonReader(JsonStyle style, OnError on_error)
    : style_(std::move(style)), on_error_(on_error) {}

void JsonReader::fail(const JsonField& field, const std::string& rule) {
  fail_at(field.pointer(), rule);
}

void JsonReader::fail_at(const std::string& pointer, const std::string& rule) {
  if (on_error_ == OnError::kThrow) throw JsonFieldError(location(pointer), pointer, rule);
  errors_.push_back(location(pointer) + ": " + rule);
}

void JsonReader::warn(const JsonField& field, const std::string& what) {
  warn_at(field.pointer(), what);
}

void JsonReader::warn_at(const std::string& pointer, const std::string& what) {
  std::string line = location(pointer) + ": " + what;
  if (warning_sink_) {
    warning_sink_(line);
  } else {
    warnings_.push_back(std::move(line));
  }
}

void JsonReader::set_warning_sink(std::function<void(const std::string&)> sink) {
  warning_sink_ = std::move(sink);
}

std::string JsonReader::location(const std::string& pointer) const {
  if (pointer.empty()) return style_.base.empty() ? style_.root : style_.base;
  if (!style_.dotted) return style_.base + pointer;
  return style_.base.empty() ? dotted(pointer) : style_.base + "." + dotted(pointer);
}

std::string JsonReader::kind(const Json& j) const {
  if (style_.wording == JsonWording::kRequest) return j.type_name();
  switch (j.type()) {
    case Json::value_t::null:
      return "null";
    case Json::value_t::boolean:
      return "a boolean";
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float:
      return "a number";
    case Json::value_t::string:
      return "a string";
    case Json::value_t::array:
      return "an array";
    case Json::value_t::object:
      return "an object";
    case Json::value_t::binary:
      return "binary data";
    case Json::value_t::discarded:
      return "nothing";
  }
  return "an unknown value";
}

void JsonReader::expected(const JsonField& field, const std::string& what) {
  fail(field, "expected " + what + ", got " + kind(*field));
}

// ---------------------------------------------------------------------------------------------
// JsonReader: presence and shape

bool JsonReader::present(const JsonField& field) {
  if (field.exists()) return true;
  fail(field, "missing (rule: required)");
  return false;
}

bool JsonReader::object(const JsonField& field) {
  if (!present(field)) return false;
  if (field->is_object()) return true;
  expected(field, "an object");
  return false;
}

bool JsonReader::array(const JsonField& field, std::size_t max_size, std::string_view what) {
  if (!present(field)) return false;
  if (!field->is_array()) {
    expected(field, "an array");
    return false;
  }
  if (field->size() > max_size) {
    fail(field, std::to_string(field->size()) + " " +
                    std::string(what.empty() ? "elements" : what) + " (rule: at most " +
                    std::to_string(max_size) + ")");
    return false;
  }
  return true;
}

void JsonReader::warn_unknown_keys(const JsonField& object,
                                   std::initializer_list<std::string_view> keys) {
  if (!object.exists() || !object->is_object()) return;
  for (const auto& [key, value] : object->items()) {
    if (!known(keys, key)) warn(object[key], "unknown key (ignored)");
  }
}

bool JsonReader::refuse_unknown_keys(const JsonField& object,
                                     std::initializer_list<std::string_view> keys) {
  if (!object.exists() || !object->is_object()) return true;
  bool ok = true;
  for (const auto& [key, value] : object->items()) {
    if (known(keys, key)) continue;
    fail(object[key], "unknown key (rule: one of " + joined(keys) + ")");
    ok = false;
  }
  return ok;
}

// ---------------------------------------------------------------------------------------------
// JsonReader: values

std::optional<double> JsonReader::number(const JsonField& field, NumberRange range) {
  if (!present(field)) return std::nullopt;
  if (!field->is_number()) {
    expected(field, "a number");
    return std::nullopt;
  }
  const double x = field->get<double>();
  if (!std::isfinite(x)) {
    fail(field, "number is not finite");
    return std::nullopt;
  }
  if (x < range.lo || x > range.hi) {
    fail(field,
         message_number(x) + " is out of range (rule: " + range_rule("a number", range) + ")");
    return std::nullopt;
  }
  return x;
}

std::optional<std::int64_t> JsonReader::integer(const JsonField& field,
                                                std::int64_t lo,
                                                std::int64_t hi) {
  if (!present(field)) return std::nullopt;
  const Json& j = *field;
  if (!j.is_number_integer()) {
    if (j.is_number()) {
      fail(field, "expected an integer, got a number with a fraction or an exponent");
    } else {
      expected(field, "an integer");
    }
    return std::nullopt;
  }
  // unsigned values above INT64_MAX compare as out of range, never as wrapped negatives
  const bool in_range = j.is_number_unsigned()
                            ? hi >= 0 && j.get<std::uint64_t>() <= static_cast<std::uint64_t>(hi) &&
                                  static_cast<std::int64_t>(j.get<std::uint64_t>()) >= lo
                            : j.get<std::int64_t>() >= lo && j.get<std::int64_t>() <= hi;
  if (!in_range) {
    fail(field, j.dump() + " is out of range (rule: an integer in [" + std::to_string(lo) + ", " +
                    std::to_string(hi) + "])");
    return std::nullopt;
  }
  return j.is_number_unsigned() ? static_cast<std::int64_t>(j.get<std::uint64_t>())
                                : j.get<std::int64_t>();
}

std::optional<bool> JsonReader::boolean(const JsonField& field) {
  if (!present(field)) return std::nullopt;
  if (!field->is_boolean()) {
    expected(field, "true or false");
    return std::nullopt;
  }
  return field->get<bool>();
}

std::optional<std::string> JsonReader::string(const JsonField& field) {
  if (!present(field)) return std::nullopt;
  if (!field->is_string()) {
    expected(field, "a string");
    return std::nullopt;
  }
  return field->get<std::string>();
}

std::optional<Eigen::VectorXd> JsonReader::numbers(const JsonField& field,
                                                   int n,
                                                   NumberRange range) {
  if (!present(field)) return std::nullopt;
  if (!field->is_array() || field->size() != static_cast<std::size_t>(n)) {
    fail(field, "expected an array of " + std::to_string(n) + " numbers, got " +
                    (field->is_array() ? "an array of " + std::to_string(field->size()) + " values"
                                       : kind(*field)));
    return std::nullopt;
  }
  Eigen::VectorXd v(n);
  bool ok = true;
  for (int k = 0; k < n; ++k) {
    const auto x = number(field[static_cast<std::size_t>(k)], range);
    if (x)
      v[k] = *x;
    else
      ok = false;
  }
  if (!ok) return std::nullopt;
  return v;
}

std::optional<Eigen::Matrix3d> JsonReader::matrix(const JsonField& field) {
  if (!present(field)) return std::nullopt;
  if (!field->is_array() || field->size() != 3) {
    fail(field, "expected an array of 3 rows of 3 numbers, got " +
                    (field->is_array() ? "an array of " + std::to_string(field->size()) + " values"
                                       : kind(*field)));
    return std::nullopt;
  }
  Eigen::Matrix3d M;
  bool ok = true;
  for (int r = 0; r < 3; ++r) {
    const auto row = vector<3>(field[static_cast<std::size_t>(r)]);
    if (row)
      M.row(r) = row->transpose();
    else
      ok = false;
  }
  if (!ok) return std::nullopt;
  return M;
}

std::optional<Eigen::Quaterniond> JsonReader::quaternion(const JsonField& field, double tolerance) {
  if (!present(field)) return std::nullopt;
  if (!field->is_array() || field->size() != 4) {
    const std::string got = !field->is_array()
                                ? kind(*field)
                                : "an array of " + std::to_string(field->size()) + " values";
    fail(field, "expected an array of 4 numbers [w, x, y, z]" +
                    (style_.wording == JsonWording::kDocument ? ", got " + got : std::string()));
    return std::nullopt;
  }
  const auto v = vector<4>(field);
  if (!v) return std::nullopt;
  Eigen::Quaterniond q((*v)[0], (*v)[1], (*v)[2], (*v)[3]);
  const double n = q.norm();
  if (!(n >= kMinQuaternionNorm && std::abs(n - 1.0) <= tolerance)) {
    const std::string rule = std::isfinite(tolerance)
                                 ? "unit length within " + message_number(tolerance)
                                 : "a quaternion of nonzero length";
    const std::string norm = message_number(n);
    fail(field,
         (style_.wording == JsonWording::kRequest ? "quaternion norm is " + norm
                                                  : "quaternion [w, x, y, z] has norm " + norm) +
             " (rule: " + rule + ")");
    return std::nullopt;
  }
  // a value unit to rounding keeps its bits (normalizing can move the last one)
  if (std::abs(q.squaredNorm() - 1.0) > 1e-14) q.normalize();
  return q;
}

// ---------------------------------------------------------------------------------------------
// JsonFields: the same checks, stopping at the first broken rule. reader_ throws, so every
// optional it returns holds a value.

void JsonFields::fail(const JsonField& field, const std::string& rule) {
  throw JsonFieldError(reader_.location(field.pointer()), field.pointer(), rule);
}

JsonField JsonFields::present(const JsonField& field) {
  reader_.present(field);
  return field;
}

JsonField JsonFields::object(const JsonField& field) {
  reader_.object(field);
  return field;
}

JsonField JsonFields::array(const JsonField& field, std::size_t max_size, std::string_view what) {
  reader_.array(field, max_size, what);
  return field;
}

void JsonFields::refuse_unknown_keys(const JsonField& object,
                                     std::initializer_list<std::string_view> known) {
  reader_.refuse_unknown_keys(object, known);
}

double JsonFields::number(const JsonField& field, NumberRange range) {
  return *reader_.number(field, range);
}

double JsonFields::number_or(const JsonField& field, double fallback, NumberRange range) {
  return field.exists() ? number(field, range) : fallback;
}

std::int64_t JsonFields::integer(const JsonField& field, std::int64_t lo, std::int64_t hi) {
  return *reader_.integer(field, lo, hi);
}

std::int64_t JsonFields::integer_or(const JsonField& field,
                                    std::int64_t fallback,
                                    std::int64_t lo,
                                    std::int64_t hi) {
  return field.exists() ? integer(field, lo, hi) : fallback;
}

bool JsonFields::boolean(const JsonField& field) { return *reader_.boolean(field); }

bool JsonFields::boolean_or(const JsonField& field, bool fallback) {
  return field.exists() ? boolean(field) : fallback;
}

std::string JsonFields::string(const JsonField& field) { return *reader_.string(field); }

Eigen::VectorXd JsonFields::numbers(const JsonField& field, int n, NumberRange range) {
  return *reader_.numbers(field, n, range);
}

Eigen::Vector3d JsonFields::vector3(const JsonField& field, NumberRange range) {
  return *reader_.vector<3>(field, range);
}

Eigen::Quaterniond JsonFields::quaternion(const JsonField& field, double tolerance) {
  return *reader_.quaternion(field, tolerance);
}

}  // namespace io
