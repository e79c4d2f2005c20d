#include "cli/json_fields.hpp"

#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>

namespace cli {

namespace {
std::string type_name(const nlohmann::json& j) { return j.type_name(); }
}  // namespace

nlohmann::json read_json_file(const std::string& path, std::size_t max_bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RequestError(path + ": cannot open the file");
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::size_t>(std::max<std::streamoff>(0, in.tellg()));
  if (size > max_bytes) {
    throw RequestError(path + ": file is " + std::to_string(size) + " bytes (rule: at most " +
                       std::to_string(max_bytes) + ")");
  }
  in.seekg(0);
  std::string text(size, '\0');
  in.read(text.data(), static_cast<std::streamsize>(size));
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // byte offset → line and column
    const std::size_t at = std::min<std::size_t>(e.byte > 0 ? e.byte - 1 : 0, text.size());
    std::size_t line = 1, col = 1;
    for (std::size_t k = 0; k < at; ++k) {
      if (text[k] == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
    throw RequestError(path + ":" + std::to_string(line) + ":" + std::to_string(col) +
                       ": invalid JSON");
  }
}

double number(const nlohmann::json& j, const std::string& field) {
  if (!j.is_number()) throw RequestError(field + ": expected a number, got " + type_name(j));
  const double x = j.get<double>();
  if (!std::isfinite(x)) throw RequestError(field + ": number is not finite");
  return x;
}

double number_or(const nlohmann::json& parent, const char* key, const std::string& field,
                 double fallback) {
  if (!parent.contains(key)) return fallback;
  return number(parent.at(key), field + "/" + key);
}

int integer_in(const nlohmann::json& j, const std::string& field, int lo, int hi) {
  if (!j.is_number_integer()) throw RequestError(field + ": expected an integer, got " + type_name(j));
  const auto x = j.get<long long>();
  if (x < lo || x > hi) {
    throw RequestError(field + ": " + std::to_string(x) + " is outside [" + std::to_string(lo) +
                       ", " + std::to_string(hi) + "]");
  }
  return static_cast<int>(x);
}

std::string string(const nlohmann::json& j, const std::string& field) {
  if (!j.is_string()) throw RequestError(field + ": expected a string, got " + type_name(j));
  return j.get<std::string>();
}

Eigen::Vector3d vector3(const nlohmann::json& j, const std::string& field) {
  if (!j.is_array() || j.size() != 3) {
    throw RequestError(field + ": expected an array of 3 numbers");
  }
  return {number(j[0], field + "/0"), number(j[1], field + "/1"), number(j[2], field + "/2")};
}

Eigen::Quaterniond quaternion_wxyz(const nlohmann::json& j, const std::string& field) {
  if (!j.is_array() || j.size() != 4) {
    throw RequestError(field + ": expected an array of 4 numbers [w, x, y, z]");
  }
  Eigen::Quaterniond q(number(j[0], field + "/0"), number(j[1], field + "/1"),
                       number(j[2], field + "/2"), number(j[3], field + "/3"));
  if (std::abs(q.norm() - 1.0) > 1e-3) {
    throw RequestError(field + ": quaternion norm is " + std::to_string(q.norm()) +
                       " (rule: a unit quaternion [w, x, y, z])");
  }
  return q.normalized();
}

void warn_unknown_keys(const nlohmann::json& object, const std::string& field,
                       std::initializer_list<const char*> known) {
  if (!object.is_object()) return;
  for (const auto& [key, value] : object.items()) {
    bool found = false;
    for (const char* k : known) found = found || key == k;
    if (!found) std::cerr << "warning: " << field << "/" << key << ": unknown key, ignored\n";
  }
}

}  // namespace cli
