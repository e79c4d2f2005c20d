#include "cli/marker_set_file.hpp"

#include <filesystem>

#include "cli/json_fields.hpp"
#include "io/bundled_characters.hpp"

namespace cli {

namespace {

constexpr std::size_t kMaxMarkers = 10000;
constexpr double kMaxOffset = 10.0;  // m: a marker farther from its link origin is a typo

ik::Marker parse_marker(io::JsonFields& f,
                        const io::JsonField& field,
                        const std::string& name,
                        const core::Model& model) {
  f.object(field);
  f.warn_unknown_keys(field, {"link", "offset", "weight"});
  ik::Marker m;
  m.name = name;
  const std::string link = f.string(field["link"]);
  m.link = model.link_index(link);
  if (m.link < 1) f.fail(field["link"], "no link '" + link + "' in " + model.name);
  m.offset_given = field["offset"].given();
  if (m.offset_given) m.offset = f.vector3(field["offset"], {-kMaxOffset, kMaxOffset});
  m.weight = f.number_or(field["weight"], 1.0, {0.0, 1e6});
  return m;
}

}  // namespace

ik::MarkerSet parse_marker_set(const nlohmann::json& doc, const core::Model& model) {
  return io::rethrow_as<RequestError>([&] {
    io::JsonFields f = request_fields();
    const io::JsonField root(doc);
    f.object(root);
    f.warn_unknown_keys(root, {"markers", "description"});
    const io::JsonField markers = f.object(root["markers"]);
    if (markers.size() == 0) f.fail(markers, "no markers (rule: at least one marker)");
    if (markers.size() > kMaxMarkers) f.fail(markers, "more than 10000 markers");
    ik::MarkerSet set;
    for (const auto& item : markers->items()) {
      const std::string& name = item.key();
      if (name.empty()) f.fail(markers, "a marker has an empty name");
      set.markers.push_back(parse_marker(f, markers[name], name, model));
    }
    return set;
  });
}

ik::MarkerSet read_marker_set_file(const std::string& path, const core::Model& model) {
  const nlohmann::json doc = read_json_file(path);
  try {
    return parse_marker_set(doc, model);
  } catch (const RequestError& e) {
    throw RequestError(path + ": " + e.what());
  }
}

std::string bundled_marker_set_path(const core::Model& model) {
  const std::filesystem::path p =
      std::filesystem::path(io::characters_dir()) / "markers" / ("cmu41_" + model.name + ".json");
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec) ? p.string() : std::string();
}

}  // namespace cli
