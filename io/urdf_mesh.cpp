#include "io/urdf_mesh.hpp"

#include <string_view>
#include <system_error>
#include <utility>

namespace io::urdf_internal {

namespace fs = std::filesystem;

namespace {

// true when p (absolute, lexically normal) lies strictly inside root (absolute, normal)
bool inside(const fs::path& p, const fs::path& root) {
  const fs::path rel = p.lexically_relative(root);
  if (rel.empty() || rel == ".") return false;
  return *rel.begin() != "..";
}

// nearest folder named `package` among `dir` and its ancestors, or empty
fs::path find_package(const fs::path& dir, const std::string& package) {
  if (dir.empty() || package.empty() || package == "." || package == ".." ||
      package.find('/') != std::string::npos) {
    return {};
  }
  for (fs::path p = dir;; p = p.parent_path()) {
    if (p.filename() == package) return p;
    if (p == p.parent_path()) return {};
  }
}

std::optional<std::pair<std::string, std::string>> split_package_uri(const std::string& uri) {
  constexpr std::string_view kPrefix = "package://";
  if (uri.rfind(kPrefix, 0) != 0) return std::nullopt;
  const std::string rest = uri.substr(kPrefix.size());
  const size_t slash = rest.find('/');
  if (slash == std::string::npos) return std::pair<std::string, std::string>{rest, ""};
  return std::pair<std::string, std::string>{rest.substr(0, slash), rest.substr(slash + 1)};
}

}  // namespace

MeshResolver::MeshResolver(const std::string& base_dir, const std::vector<std::string>& uris) {
  if (base_dir.empty()) return;
  std::error_code ec;
  urdf_dir_ = fs::weakly_canonical(fs::absolute(base_dir, ec), ec).lexically_normal();
  if (ec) urdf_dir_ = fs::absolute(base_dir).lexically_normal();
  root_ = urdf_dir_;
  // the first package:// that resolves to an ancestor makes that package the model folder
  for (const std::string& uri : uris) {
    if (auto pkg = split_package_uri(uri)) {
      const fs::path dir = find_package(urdf_dir_, pkg->first);
      if (!dir.empty()) {
        root_ = dir;
        break;
      }
    }
  }
}

std::optional<std::string> MeshResolver::resolve(const std::string& uri, std::string& why) const {
  if (root_.empty()) {
    why = "cannot be resolved: no model folder was given (URDF text without a base folder)";
    return std::nullopt;
  }
  if (uri.empty()) {
    why = "has an empty filename";
    return std::nullopt;
  }
  fs::path candidate;
  if (auto pkg = split_package_uri(uri)) {
    const fs::path dir = find_package(urdf_dir_, pkg->first);
    if (dir.empty()) {
      why = "names package '" + pkg->first + "', but no folder of that name contains " +
            urdf_dir_.string() +
            " (rule: package://PKG resolves to the nearest ancestor "
            "folder named PKG)";
      return std::nullopt;
    }
    candidate = dir / pkg->second;
  } else if (uri.rfind("file://", 0) == 0) {
    const fs::path p = uri.substr(7);
    candidate = p.is_absolute() ? p : urdf_dir_ / p;
  } else if (uri.find("://") != std::string::npos) {
    why = "uses the URI scheme '" + uri.substr(0, uri.find("://")) +
          "', which is not supported (supported: package://, file://, plain paths)";
    return std::nullopt;
  } else {
    const fs::path p = uri;
    candidate = p.is_absolute() ? p : urdf_dir_ / p;
  }
  candidate = candidate.lexically_normal();
  const std::string rule =
      " (rule: meshes must lie inside the model folder " + root_.string() + "); refused";
  if (!inside(candidate, root_)) {
    why = "resolves to " + candidate.string() + ", outside the model folder" + rule;
    return std::nullopt;
  }
  std::error_code ec;
  if (!fs::exists(candidate, ec)) {
    why = "was not found (looked for " + candidate.string() + ")";
    return std::nullopt;
  }
  const fs::path real = fs::canonical(candidate, ec);
  if (ec) {
    why = "cannot be resolved: " + ec.message();
    return std::nullopt;
  }
  if (!inside(real, root_)) {
    why = "resolves through a symbolic link to " + real.string() + ", outside the model folder" +
          rule;
    return std::nullopt;
  }
  if (!fs::is_regular_file(real, ec)) {
    why = "resolves to " + real.string() + ", which is not a regular file";
    return std::nullopt;
  }
  return real.lexically_relative(root_).generic_string();
}

}  // namespace io::urdf_internal
