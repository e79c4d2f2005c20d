#include "cli/c3d_markers.hpp"

#include "cli/json_fields.hpp"

namespace cli {

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
    throw RequestError("no marker of the marker set is in the trial (its labels: " +
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

}  // namespace cli
