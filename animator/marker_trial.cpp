#include "animator/marker_trial.hpp"

#include <filesystem>

#include "ik/marker_calibration.hpp"
#include "io/bundled_characters.hpp"
#include "io/json_parse.hpp"
#include "io/json_reader.hpp"

namespace animator {

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

ik::MarkerSet parse_marker_set(const nlohmann::json& doc,
                               const core::Model& model,
                               const std::function<void(const std::string&)>& warn) {
  return io::rethrow_as<MarkerSetError>([&] {
    io::JsonFields f(io::JsonStyle{.root = "/", .wording = io::JsonWording::kRequest});
    if (warn) f.set_warning_sink(warn);
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

std::string bundled_marker_set_path(const core::Model& model) {
  const std::filesystem::path p =
      std::filesystem::path(io::characters_dir()) / "markers" / ("cmu41_" + model.name + ".json");
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec) ? p.string() : std::string();
}

TrialMarkers markers_from_c3d(const io::C3dTrial& trial, const ik::MarkerSet& set) {
  TrialMarkers out;
  ik::MarkerTrajectories& t = out.trajectories;
  t.rate_hz = trial.rate_hz;
  t.frames = trial.frame_count();
  t.markers = set.size();
  t.positions.assign(static_cast<size_t>(t.frames) * t.markers, core::Vector3::Zero());
  t.present.assign(static_cast<size_t>(t.frames) * t.markers, 0);
  std::vector<int> column(set.size(), -1);
  for (int j = 0; j < set.size(); ++j) {
    column[j] = trial.find(set.markers[j].name);
    if (column[j] < 0) out.not_in_trial.push_back(set.markers[j].name);
  }
  if (static_cast<int>(out.not_in_trial.size()) == set.size()) {
    throw MarkerSetError("no marker of the marker set is in the trial (its labels: " +
                         (trial.labels.empty() ? std::string("none") : trial.labels.front()) +
                         (trial.labels.size() > 1 ? ", …)" : ")"));
  }
  for (int p = 0; p < trial.point_count(); ++p) {
    if (set.find(trial.labels[p]) < 0) out.unused.push_back(trial.labels[p]);
  }
  const int points = trial.point_count();
  for (int f = 0; f < t.frames; ++f) {
    for (int j = 0; j < set.size(); ++j) {
      const int p = column[j];
      const size_t from = static_cast<size_t>(f) * points + p;
      if (p < 0 || !trial.present[from]) continue;
      const size_t to = static_cast<size_t>(f) * t.markers + j;
      t.positions[to] = ik::lab_to_world(trial.positions[from]);
      t.present[to] = 1;
    }
  }
  return out;
}

FittedTrial fit_trial(const io::C3dTrial& trial, const core::Model& model) {
  const std::string set_path = bundled_marker_set_path(model);
  if (set_path.empty()) {
    throw MarkerSetError("no marker set for the character '" + model.name +
                         "' (rule: a marker trial is fitted onto a human figure with a bundled "
                         "marker set: human48 or human34)");
  }
  const ik::MarkerSet set =
      parse_marker_set(io::read_json_file(set_path, {}, "a marker set"), model);
  const TrialMarkers markers = markers_from_c3d(trial, set);
  ik::CalibrationSettings calibration;
  calibration.estimate_scales = false;
  // the calibration reads the model through a shared pointer; this one does not own it
  const std::shared_ptr<const core::Model> borrowed(std::shared_ptr<const core::Model>(), &model);
  const ik::CalibrationResult c =
      ik::calibrate_markers(borrowed, set, markers.trajectories, {}, calibration);
  FittedTrial out;
  out.clip = ik::fit_trajectories(model, c.set, markers.trajectories).clip;
  out.markers = make_clip_markers(model, c.set, markers.trajectories);
  return out;
}

}  // namespace animator
