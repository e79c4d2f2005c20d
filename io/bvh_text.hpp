// Small text helpers shared by the BVH reader, importer and writer (internal to io/bvh_*.cpp).
#pragma once

#include <cstddef>
#include <cstdio>
#include <numbers>
#include <string>
#include <string_view>

namespace io::bvh_detail {

/// Blanks between BVH tokens: space, tab, CR, FF, VT (newline counts lines and is apart).
inline bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

/// ASCII lower case; other bytes unchanged.
inline char lower(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

/// ASCII case-insensitive equality (keywords and channel names).
inline bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (lower(a[i]) != lower(b[i])) return false;
  }
  return true;
}

/// Degrees to radians: BVH rotation channels are in degrees.
inline constexpr double kDegree = std::numbers::pi / 180.0;

/// A number as it appears in a message (%.9g).
inline std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

}  // namespace io::bvh_detail
