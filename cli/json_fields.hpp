// Reading request files: typed fields with errors that name the field (as a JSON pointer).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

namespace cli {

/// A bad request: what() names the field and the rule.
class RequestError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Parses a request file (size-capped); errors carry the line and column of a syntax error.
nlohmann::json read_json_file(const std::string& path, std::size_t max_bytes = 16u << 20);

double number(const nlohmann::json& j, const std::string& field);
double number_or(const nlohmann::json& parent, const char* key, const std::string& field,
                 double fallback);
int integer_in(const nlohmann::json& j, const std::string& field, int lo, int hi);
std::string string(const nlohmann::json& j, const std::string& field);
Eigen::Vector3d vector3(const nlohmann::json& j, const std::string& field);
/// [w, x, y, z], normalized; must have a norm within 1e-3 of 1
Eigen::Quaterniond quaternion_wxyz(const nlohmann::json& j, const std::string& field);
/// Warns on stderr about keys of `object` that are not in `known`.
void warn_unknown_keys(const nlohmann::json& object, const std::string& field,
                       std::initializer_list<const char*> known);

}  // namespace cli
