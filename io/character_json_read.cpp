// Character JSON text to a Model: a bounded parse (io/json_parse.hpp), the header, every link
// (character_json_links.cpp) and the tree rules (character_json_structure.cpp), all errors of a
// file collected with their pointers; then the builder checks the physical rules, and the axes and
// quaternions it renormalizes get the file's exact bits back so that load(write(m)) == m.
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <system_error>
#include <unordered_map>
#include <utility>

#include "io/character_json_internal.hpp"
#include "io/read_file.hpp"

namespace io {

using namespace core;  // io reads and writes core's types

namespace {

using namespace character_json;

std::vector<std::string> capped(const std::string& source,
                                const std::vector<std::string>& lines,
                                const char* what) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < lines.size() && i < kMaxReported; ++i) {
    out.push_back(source + ": " + lines[i]);
  }
  if (lines.size() > kMaxReported) {
    out.push_back(source + ": ... and " + std::to_string(lines.size() - kMaxReported) + " more " +
                  what);
  }
  return out;
}

[[noreturn]] void throw_errors(const std::string& source, const std::vector<std::string>& lines) {
  throw ModelError(capped(source, lines, "errors"));
}

void throw_if_errors(const std::string& source, const CharacterReader& rd) {
  if (!rd.errors().empty()) throw_errors(source, rd.errors());
}

// "format" and "version" identify the file; nothing else is read when they are wrong.
void read_header(CharacterReader& rd, const JsonField& doc, const std::string& src) {
  if (!rd.object(doc)) throw_errors(src, rd.errors());
  rd.warn_unknown_keys(doc, {"format", "version", "name", "gravity", "links"});
  if (const JsonField f = doc["format"]) {
    if (auto s = rd.string(f); s && *s != kCharacterFormat) {
      rd.fail(f, "is " + in_quotes(*s) + " (rule: \"" + kCharacterFormat + "\")");
    }
  } else {
    rd.fail(f, std::string("missing (rule: \"format\": \"") + kCharacterFormat +
                   "\" identifies a character file)");
  }
  const std::string version = std::to_string(kCharacterFormatVersion);
  if (const JsonField v = doc["version"]) {
    const auto n = rd.integer(v, std::numeric_limits<int>::min(), std::numeric_limits<int>::max());
    if (n && *n != kCharacterFormatVersion) {
      rd.fail(v, "version " + std::to_string(*n) + " is not supported (rule: " + version + ")");
    }
  } else {
    rd.fail(v, "missing (rule: \"version\": " + version + ")");
  }
  throw_if_errors(src, rd);
}

struct Links {
  std::vector<LinkSpec> specs;
  std::vector<LinkInfo> info;
};

// The links, counted before anything is read, and their tree rules.
Links read_links(CharacterReader& rd,
                 const JsonField& doc,
                 const std::string& src,
                 const std::string& base_dir) {
  const JsonField links = doc["links"];
  if (!links) {
    rd.fail(links, "missing (rule: a character has an array of links)");
    throw_errors(src, rd.errors());
  }
  if (!rd.array(links, static_cast<std::size_t>(kMaxLinks), "links"))
    throw_errors(src, rd.errors());
  if (links.size() == 0) {
    rd.fail(links, "no links (rule: at least one link)");
    throw_errors(src, rd.errors());
  }
  Links out;
  out.specs.resize(links.size());
  out.info.resize(links.size());
  for (std::size_t k = 0; k < links.size(); ++k) {
    read_link(rd, links[k], out.specs[k], out.info[k], base_dir);
  }
  throw_if_errors(src, rd);
  check_structure(rd, out.specs, out.info);
  throw_if_errors(src, rd);
  return out;
}

// The builder checks the physical rules; its messages get the pointer of the field.
std::shared_ptr<const Model> build(ModelBuilder& b, const Links& links, const std::string& src) {
  for (const LinkSpec& l : links.specs) b.add_link(l);
  try {
    return b.finalize();
  } catch (const ModelError& e) {
    std::unordered_map<std::string, std::size_t> by_name, by_joint;
    for (std::size_t k = 0; k < links.specs.size(); ++k) {
      const LinkSpec& l = links.specs[k];
      by_name.emplace(l.name, k);
      by_joint.emplace(l.joint.name.empty() ? l.name : l.joint.name, k);
    }
    std::vector<std::string> lines;
    for (const std::string& v : e.violations()) {
      lines.push_back(locate_violation(v, by_name, by_joint, links.info) + ": " + v);
    }
    throw_errors(src, lines);
  }
}

// The builder renormalizes axes and quaternions, which can move the last bit of a value that is
// already unit; the file's bits are restored so that load(write(m)) == m.
void restore_bits(Model& model,
                  const Links& links,
                  const std::unordered_map<std::string, int>& index) {
  for (std::size_t k = 0; k < links.specs.size(); ++k) {
    const int i = index.at(links.specs[k].name);
    const LinkInfo& li = links.info[k];
    if (li.axis && one_dof(model.joint_type[i]) &&
        std::abs(li.axis->squaredNorm() - 1.0) <= kUnitTolerance) {
      model.axis[i] = *li.axis;
      model.axis_index[i] = -1;
      for (int a = 0; a < 3; ++a) {
        if (model.axis[i] == Vector3::Unit(a)) model.axis_index[i] = a;
      }
    }
    if (model.joint_type[i] == JointType::kSpherical) {
      if (li.range_frame) model.spherical_range[i].frame = *li.range_frame;
      if (li.standard_orientation) model.standard_orientation[i] = *li.standard_orientation;
    }
  }
}

}  // namespace

LoadResult load_character_json_string(const std::string& text,
                                      const std::string& source_name,
                                      const std::string& base_dir) {
  const std::string& src = source_name;
  if (text.size() > kMaxCharacterJsonBytes) {
    throw ModelError(
        {src + ": " + std::to_string(text.size()) + " bytes is too large (rule: at most 64 MiB)"});
  }
  nlohmann::json document;
  try {
    document = parse_json(text, src, {.max_bytes = kMaxCharacterJsonBytes});
  } catch (const JsonParseError& e) {
    throw ModelError({e.what()});
  }
  const JsonField doc(document);

  CharacterReader rd;
  read_header(rd, doc, src);
  std::string name = std::filesystem::path(src).stem().string();
  if (const JsonField n = doc["name"]) {
    if (auto s = rd.string(n)) name = *s;
  }
  Vector3 gravity(0, -9.81, 0);
  if (const JsonField g = doc["gravity"]) {
    if (auto v = rd.vector<3>(g)) gravity = *v;
  }
  const Links links = read_links(rd, doc, src, base_dir);

  ModelBuilder b(name);
  b.set_gravity(gravity);
  b.set_source_dir(base_dir);
  const std::shared_ptr<const Model> built = build(b, links, src);

  // the inertia about the link frame must stay finite (m |c|² can overflow where m and c do not)
  std::unordered_map<std::string, int> index;
  for (int i = 1; i < built->njoints; ++i) index.emplace(built->link_name[i], i);
  for (std::size_t k = 0; k < links.specs.size(); ++k) {
    const SpatialInertia& S = built->inertia[index.at(links.specs[k].name)];
    if (!S.h.allFinite() || !S.I_O.allFinite()) {
      rd.fail_at(json_pointer(links.info[k].ptr, "inertial"),
                 "the inertia about the link frame overflows (rule: mass × com and mass × "
                 "|com|² plus the inertia are finite)");
    }
  }
  throw_if_errors(src, rd);

  auto model = std::make_shared<Model>(*built);
  restore_bits(*model, links, index);
  LoadResult result;
  result.model = std::move(model);
  result.warnings = capped(src, rd.warnings(), "warnings");
  return result;
}

LoadResult load_character_json_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) {
    throw ModelError({path + ": cannot open the file" + (ec ? ": " + ec.message() : "")});
  }
  if (!fs::is_regular_file(st)) {
    throw ModelError({path + ": not a regular file (rule: a character file is a plain file)"});
  }
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw ModelError({path + ": cannot read the file size: " + ec.message()});
  if (size > kMaxCharacterJsonBytes) {
    throw ModelError(
        {path + ": the file is " + std::to_string(size) + " bytes (rule: at most 64 MiB)"});
  }
  std::string text;
  try {
    text = read_file(path, kMaxCharacterJsonBytes, "a character file");
  } catch (const FileError& e) {
    throw ModelError({e.what()});
  }
  fs::path dir = fs::absolute(fs::path(path), ec).parent_path();
  if (ec) dir = fs::path(path).parent_path();
  return load_character_json_string(text, path, dir.lexically_normal().string());
}

}  // namespace io
