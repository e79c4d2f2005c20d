#include "ik/marker_calibration.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/configuration.hpp"
#include "core/kinematics.hpp"

namespace ik {

namespace {

// Frames of the calibration range with enough markers, evenly thinned to max_frames.
std::vector<int> calibration_frames(const MarkerTrajectories& t,
                                    const CalibrationSettings& s,
                                    int min_markers) {
  const auto enough_markers = [&](int f) {
    int n = 0;
    for (int j = 0; j < t.markers; ++j) n += t.frame_present(f)[j] ? 1 : 0;
    return n >= min_markers;
  };
  int first = std::clamp(s.first_frame, 0, std::max(0, t.frames - 1));
  if (s.last_frame < 0) {
    // the default second starts where the subject is first seen (a trial often starts with the
    // subject outside the capture volume)
    while (first + 1 < t.frames && !enough_markers(first)) ++first;
  }
  const int second = std::max(1, static_cast<int>(std::lround(t.rate_hz)));
  const int last = std::clamp(s.last_frame < 0 ? first + second : s.last_frame, first, t.frames);
  std::vector<int> usable;
  for (int f = first; f < last; ++f) {
    if (enough_markers(f)) usable.push_back(f);
  }
  if (usable.empty()) {
    throw std::invalid_argument("calibration: no frame in [" + std::to_string(first) + ", " +
                                std::to_string(last) + ") has enough markers");
  }
  const int n = std::min<int>(usable.size(), std::max(1, s.max_frames));
  std::vector<int> out(n);
  for (int k = 0; k < n; ++k) out[k] = usable[(k * static_cast<long>(usable.size())) / n];
  return out;
}

// Step (b): offsets as regularized means of the link-frame marker positions.
struct OffsetSums {
  std::vector<core::Vector3> sum;
  std::vector<int> count;
};

void add_offset_sample(const core::Data& data,
                       const MarkerSet& set,
                       const core::Vector3* m,
                       const std::uint8_t* present,
                       OffsetSums& sums) {
  for (int j = 0; j < set.size(); ++j) {
    if (!present[j]) continue;
    sums.sum[j] += data.X_W[set.markers[j].link].inverse_apply(m[j]);
    ++sums.count[j];
  }
}

// Rotation R about the link origin that best maps the given offsets onto the estimated ones,
// argmin Σ |R g_j − e_j|² (Kabsch without centring: the link origin is the joint).
core::Matrix3 link_rotation(const std::vector<core::Vector3>& g,
                            const std::vector<core::Vector3>& e) {
  core::Matrix3 H = core::Matrix3::Zero();
  for (size_t j = 0; j < g.size(); ++j) H += g[j] * e[j].transpose();
  Eigen::JacobiSVD<core::Matrix3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  core::Matrix3 D = core::Matrix3::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixV() * D * svd.matrixU().transpose();
}

// Rotating all of a link's offsets together is the same as rotating its joint: that gauge is
// fixed by the given offsets, so each link's estimated offsets are turned back by the rotation
// that best maps the given onto the estimated ones (links with 2 or more given offsets).
void remove_link_rotations(const MarkerSet& given, std::vector<core::Vector3>& offsets) {
  std::vector<int> links;
  for (const Marker& m : given.markers) {
    if (std::find(links.begin(), links.end(), m.link) == links.end()) links.push_back(m.link);
  }
  for (const int link : links) {
    std::vector<core::Vector3> g, e;
    for (int j = 0; j < given.size(); ++j) {
      if (given.markers[j].link != link || !given.markers[j].offset_given) continue;
      g.push_back(given.markers[j].offset);
      e.push_back(offsets[j]);
    }
    if (g.size() < 2) continue;
    const core::Matrix3 R = link_rotation(g, e);
    for (int j = 0; j < given.size(); ++j) {
      if (given.markers[j].link == link) offsets[j] = R.transpose() * offsets[j];
    }
  }
}

void update_offsets(const MarkerSet& given,
                    const CalibrationSettings& s,
                    const OffsetSums& sums,
                    MarkerFitter& fitter) {
  std::vector<core::Vector3> offsets(given.size());
  for (int j = 0; j < given.size(); ++j) {
    const Marker& g = given.markers[j];
    const double lambda = g.offset_given ? s.offset_prior : 0.0;
    const double n = sums.count[j] + lambda;
    const bool keep = (g.offset_given && !s.estimate_given_offsets) || n <= 0;
    offsets[j] = keep ? fitter.marker_set().markers[j].offset
                      : core::Vector3((sums.sum[j] + lambda * g.offset) / n);
  }
  remove_link_rotations(given, offsets);
  for (int j = 0; j < given.size(); ++j) fitter.set_offset(j, offsets[j]);
}

// Step (c): accumulates the normal equations of the scales at one fitted pose.
void add_scale_sample(const core::Model& model,
                      const std::vector<core::Vector3>& base,
                      const core::Data& data,
                      const MarkerSet& set,
                      const core::Vector3* m,
                      const std::uint8_t* present,
                      Eigen::MatrixXd& N,
                      Eigen::VectorXd& b) {
  Eigen::Matrix<double, 3, Eigen::Dynamic> D(3, model.njoints);
  for (int j = 0; j < set.size(); ++j) {
    if (!present[j]) continue;
    const Marker& mk = set.markers[j];
    D.setZero();
    for (int c = mk.link; c > 1; c = model.parent[c]) {
      const int k = model.parent[c];
      D.col(k) += data.X_W[k].R * base[c];
    }
    const core::Vector3 e = m[j] - data.X_W[mk.link] * mk.offset;
    N.noalias() += mk.weight * D.transpose() * D;
    b.noalias() += mk.weight * D.transpose() * e;
  }
}

}  // namespace

std::shared_ptr<const core::Model> scale_joint_placements(const core::Model& model,
                                                          const std::vector<double>& scales) {
  auto out = std::make_shared<core::Model>(model);
  for (int c = 2; c < model.njoints; ++c)
    out->X_PJ[c].p = model.X_PJ[c].p * scales[model.parent[c]];
  return out;
}

namespace {

// The calibration's own copy of the model: its joint placements change between rounds (the
// fitter refers to it), so it is private to one calibration and never shared.
struct Calibration {
  Calibration(const core::Model& m, const MarkerSet& set, const MarkerFitSettings& fit)
      : work(m), base(m.njoints), scales(m.njoints, 1.0), fitter(work, set, fit), data(work) {
    for (int c = 0; c < m.njoints; ++c) base[c] = m.X_PJ[c].p;
  }
  void apply_scales() {
    for (int c = 2; c < work.njoints; ++c) work.X_PJ[c].p = base[c] * scales[work.parent[c]];
  }
  core::Model work;
  std::vector<core::Vector3> base;
  std::vector<double> scales;
  MarkerFitter fitter;
  core::Data data;
};

// Step (a) for every calibration frame, warm-started from its previous pose; returns the RMS.
double fit_poses(Calibration& c,
                 const MarkerTrajectories& t,
                 const std::vector<int>& frames,
                 std::vector<Eigen::VectorXd>& poses,
                 int iterations,
                 OffsetSums& sums) {
  double sum2 = 0;
  int n = 0;
  for (size_t k = 0; k < frames.size(); ++k) {
    const core::Vector3* m = t.frame_positions(frames[k]);
    const std::uint8_t* present = t.frame_present(frames[k]);
    const FrameFit r = c.fitter.fit(m, present, poses[k], iterations);
    sum2 += r.rms * r.rms * r.present;
    n += r.present;
    add_offset_sample(c.fitter.data(), c.fitter.marker_set(), m, present, sums);
  }
  return n > 0 ? std::sqrt(sum2 / n) : 0.0;
}

// Step (c): one Gauss–Newton step on the scales at the fitted poses, ridge toward 1.
void update_scales(Calibration& c,
                   const MarkerTrajectories& t,
                   const std::vector<int>& frames,
                   const std::vector<Eigen::VectorXd>& poses,
                   const CalibrationSettings& s) {
  const int n = c.work.njoints;
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  for (size_t k = 0; k < frames.size(); ++k) {
    core::forward_kinematics(c.work, c.data, poses[k]);
    add_scale_sample(c.work, c.base, c.data, c.fitter.marker_set(), t.frame_positions(frames[k]),
                     t.frame_present(frames[k]), N, b);
  }
  for (int k = 0; k < n; ++k) {
    N(k, k) += s.scale_prior;
    b[k] += s.scale_prior * (1.0 - c.scales[k]);
  }
  const Eigen::VectorXd ds = N.ldlt().solve(b);
  for (int k = 1; k < n; ++k) {
    if (std::isfinite(ds[k]))
      c.scales[k] = std::clamp(c.scales[k] + ds[k], s.min_scale, s.max_scale);
  }
  c.apply_scales();
}

// Poses of the calibration frames from a frame-by-frame fit of the range they span.
std::vector<Eigen::VectorXd> initial_poses(const core::Model& model,
                                           const MarkerSet& set,
                                           const MarkerTrajectories& t,
                                           const std::vector<int>& frames,
                                           const MarkerFitSettings& fit) {
  MarkerTrajectories range;
  range.rate_hz = t.rate_hz;
  range.markers = t.markers;
  range.frames = frames.back() - frames.front() + 1;
  const size_t begin = static_cast<size_t>(frames.front()) * t.markers;
  const size_t end = begin + static_cast<size_t>(range.frames) * t.markers;
  range.positions.assign(t.positions.begin() + begin, t.positions.begin() + end);
  range.present.assign(t.present.begin() + begin, t.present.begin() + end);
  const MarkerFitResult r = fit_trajectories(model, set, range, fit);
  std::vector<Eigen::VectorXd> poses;
  for (const int f : frames) poses.push_back(r.clip.frames[f - frames.front()]);
  return poses;
}

}  // namespace

CalibrationResult calibrate_markers(std::shared_ptr<const core::Model> model,
                                    const MarkerSet& set,
                                    const MarkerTrajectories& trajectories,
                                    const MarkerFitSettings& fit,
                                    const CalibrationSettings& settings) {
  const MarkerTrajectories& t = trajectories;
  const std::vector<int> frames = calibration_frames(t, settings, fit.min_markers);
  Calibration c(*model, set, fit);
  // first poses: a sequential fit through the whole range, so each starts near its answer
  std::vector<Eigen::VectorXd> poses = initial_poses(*model, set, t, frames, fit);
  CalibrationResult r;
  // each round fits the poses, then re-estimates offsets and scales; the last fit is with the
  // final offsets and scales
  for (int round = 0;; ++round) {
    OffsetSums sums{std::vector<core::Vector3>(set.size(), core::Vector3::Zero()),
                    std::vector<int>(set.size(), 0)};
    const double rms = fit_poses(c, t, frames, poses, 2 * fit.max_iterations, sums);
    // converged: the round before barely lowered the RMS (a round that raised it goes on)
    const double gain = r.rms_per_round.empty() ? rms : r.rms_per_round.back() - rms;
    r.rms_per_round.push_back(rms);
    if ((gain >= 0 && gain <= settings.rms_tolerance * rms) || round >= settings.max_rounds) break;
    update_offsets(set, settings, sums, c.fitter);
    if (settings.estimate_scales) update_scales(c, t, frames, poses, settings);
  }
  r.model = scale_joint_placements(*model, c.scales);
  r.set = c.fitter.marker_set();
  r.scales = c.scales;
  r.frames_used = static_cast<int>(frames.size());
  return r;
}

}  // namespace ik
