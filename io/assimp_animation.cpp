#include "io/assimp_animation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/configuration.hpp"

namespace io::assimp_detail {

namespace {

// most frames one clip may have after resampling
constexpr double kMaxFrames = 1e6;

Vector3 key_value(const aiVectorKey& k) { return Vector3(k.mValue.x, k.mValue.y, k.mValue.z); }
Quaternion key_value(const aiQuatKey& k) {
  return Quaternion(k.mValue.w, k.mValue.x, k.mValue.y, k.mValue.z);
}

// key search and interpolation of one channel component; keys are sorted by time; without keys,
// the node's rest value
template <typename Key, typename V, typename Lerp>
V sample_keys(const Key* keys, unsigned n, double t, const V& rest, Lerp lerp) {
  if (n == 0) return rest;
  const Key* end = keys + n;
  const Key* hi =
      std::upper_bound(keys, end, t, [](double x, const Key& k) { return x < k.mTime; });
  if (hi == keys) return key_value(keys[0]);
  if (hi == end) return key_value(keys[n - 1]);
  const Key& a = *(hi - 1);
  const Key& b = *hi;
  const double span = b.mTime - a.mTime;
  if (!(span > 0)) return key_value(b);
  return lerp(key_value(a), key_value(b), (t - a.mTime) / span);
}

// keys of one component of a channel must be sorted for the binary search (assimp's importers
// sort them); widens [lo, hi] to their times
template <typename Key>
void check_keys(const aiAnimation& a,
                const aiNodeAnim& ch,
                const Key* keys,
                unsigned n,
                double& lo,
                double& hi) {
  for (unsigned k = 1; k < n; ++k) {
    if (keys[k].mTime < keys[k - 1].mTime) {
      throw std::runtime_error("animation '" + std::string(a.mName.C_Str()) + "', node '" +
                               ch.mNodeName.C_Str() + "': key times decrease");
    }
  }
  if (n == 0) return;
  const double first = keys[0].mTime, last = keys[n - 1].mTime;
  if (!std::isfinite(first) || !std::isfinite(last)) {
    throw std::runtime_error("animation '" + std::string(a.mName.C_Str()) +
                             "' has a non-finite key time");
  }
  lo = std::min(lo, first);
  hi = std::max(hi, last);
}

}  // namespace

void check_budget(const AnimInfo& info,
                  const ClipBudget& budget,
                  double frame_rate,
                  std::int64_t per_frame) {
  const std::string why = clip_budget_refusal(budget, info.frames, 1.0 / frame_rate, per_frame);
  if (why.empty()) return;
  throw std::runtime_error("animation '" + std::string(info.anim->mName.C_Str()) + "' (" +
                           num((info.end - info.start) / info.ticks_per_second) +
                           " s from its first to its last key, at " + num(frame_rate) +
                           " frames per second): " + why);
}

AnimInfo anim_info(const aiAnimation& a,
                   const SceneNodes& scene,
                   double frame_rate,
                   const ClipBudget& budget,
                   Warnings& warnings) {
  AnimInfo info;
  info.anim = &a;
  info.channel_of_node.assign(scene.nodes.size(), nullptr);
  info.ticks_per_second = a.mTicksPerSecond;
  if (!(info.ticks_per_second > 0) || !std::isfinite(info.ticks_per_second)) {
    info.ticks_per_second = 25;
    warnings.add("animation '" + std::string(a.mName.C_Str()) +
                 "' does not say its ticks per second; 25 assumed (assimp's default)");
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (unsigned c = 0; c < a.mNumChannels; ++c) {
    const aiNodeAnim* ch = a.mChannels[c];
    const auto it = scene.by_name.find(ch->mNodeName.C_Str());
    if (it == scene.by_name.end()) {
      warnings.add("animation '" + std::string(a.mName.C_Str()) + "': channel for '" +
                   ch->mNodeName.C_Str() + "' has no node; ignored");
      continue;
    }
    if (info.channel_of_node[it->second] == nullptr) info.channel_of_node[it->second] = ch;
    check_keys(a, *ch, ch->mPositionKeys, ch->mNumPositionKeys, lo, hi);
    check_keys(a, *ch, ch->mRotationKeys, ch->mNumRotationKeys, lo, hi);
    check_keys(a, *ch, ch->mScalingKeys, ch->mNumScalingKeys, lo, hi);
  }
  if (!(hi >= lo)) lo = hi = 0;
  info.start = lo;
  info.end = hi;
  const double seconds = (hi - lo) / info.ticks_per_second;
  // key times are often single precision (glTF): a last key within a thousandth of a frame
  // past a frame time does not get a frame of its own
  const double n = std::ceil(seconds * frame_rate - 1e-3) + 1;
  if (!(n <= kMaxFrames)) {
    throw std::runtime_error("animation '" + std::string(a.mName.C_Str()) + "' lasts " +
                             num(seconds) + " s: more than " + num(kMaxFrames) + " frames");
  }
  info.frames = static_cast<int>(n);
  check_budget(info, budget, frame_rate, 0);
  return info;
}

double tick_of_frame(const AnimInfo& info, int k, double frame_rate) {
  return std::min(info.end, info.start + k / frame_rate * info.ticks_per_second);
}

Matrix4 local_at(const Node& node, const aiNodeAnim* ch, double t) {
  if (ch == nullptr) return node.local_rest;
  const auto lerp3 = [](const Vector3& a, const Vector3& b, double f) {
    return Vector3(a + f * (b - a));
  };
  const auto slerp = [](const Quaternion& a, const Quaternion& b, double f) {
    return a.slerp(f, b);
  };
  const Vector3 T = sample_keys(ch->mPositionKeys, ch->mNumPositionKeys, t, node.rest_t, lerp3);
  const Quaternion R =
      sample_keys(ch->mRotationKeys, ch->mNumRotationKeys, t, node.rest_r, slerp).normalized();
  const Vector3 S = sample_keys(ch->mScalingKeys, ch->mNumScalingKeys, t, node.rest_s, lerp3);
  return trs(T, R, S);
}

LinkPoses::LinkPoses(const SceneNodes& nodes, const Skeleton& skeleton, const WorldAxes& world)
    : nodes_(nodes), skeleton_(skeleton), world_(world) {}

void LinkPoses::at(const AnimInfo& info,
                   double t,
                   std::vector<Transform>& out,
                   double& scale_error) {
  const std::vector<Node>& nodes = nodes_.nodes;
  const std::vector<int>& links = skeleton_.links;
  // the root's global transform: its ancestors may be animated too
  std::vector<int> chain;
  for (int n = skeleton_.root; n >= 0; n = nodes[n].parent) chain.push_back(n);
  Matrix4 G = Matrix4::Identity();
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    G = G * local_at(nodes[*it], info.channel_of_node[*it], t);
  }
  global_.resize(links.size());
  global_[0] = G;
  for (std::size_t k = 1; k < links.size(); ++k) {
    // nodes between a link and its parent link do not exist: links are contiguous paths
    const int n = links[k];
    global_[k] = global_[skeleton_.parent_link[k]] * local_at(nodes[n], info.channel_of_node[n], t);
  }
  out.resize(links.size());
  for (std::size_t k = 0; k < links.size(); ++k) {
    double e = 0;
    out[k] = rigid(world_.A * global_[k], e);
    scale_error = std::max(scale_error, e);
  }
}

Motion sample_motion(const aiScene& scene,
                     const SceneNodes& nodes,
                     const Skeleton& s,
                     LinkPoses& poses,
                     const ImportOptions& options,
                     Warnings& warnings) {
  const std::size_t nl = s.links.size();
  Motion out;
  out.is_free.assign(nl, 0);
  out.is_free[0] = 1;
  out.dropped.assign(nl, 0.0);
  // range of each bone's offset from its parent link over every frame
  std::vector<Vector3> lo(nl, Vector3::Constant(std::numeric_limits<double>::infinity()));
  std::vector<Vector3> hi(nl, Vector3::Constant(-std::numeric_limits<double>::infinity()));
  double scale_error = 0;
  std::vector<Transform> X;
  for (unsigned a = 0; a < scene.mNumAnimations; ++a) {
    out.anims.push_back(
        anim_info(*scene.mAnimations[a], nodes, options.frame_rate, options.budget, warnings));
    const AnimInfo& info = out.anims.back();
    for (int k = 0; k < info.frames; ++k) {
      poses.at(info, tick_of_frame(info, k, options.frame_rate), X, scale_error);
      for (std::size_t j = 1; j < nl; ++j) {
        const Vector3 p_rel = X[s.parent_link[j]].inverse_apply(X[j].p);
        lo[j] = lo[j].cwiseMin(p_rel);
        hi[j] = hi[j].cwiseMax(p_rel);
        const Vector3 bind_rel = s.bind[s.parent_link[j]].inverse_apply(s.bind[j].p);
        out.dropped[j] = std::max(out.dropped[j], (p_rel - bind_rel).norm());
      }
    }
  }
  for (std::size_t j = 1; j < nl; ++j) {
    if (lo[j].x() > hi[j].x()) continue;  // no frames
    const double moves = (hi[j] - lo[j]).norm();
    if (moves > options.translating_tolerance) {
      out.is_free[j] = 1;
      warnings.add("bone '" + s.link_name[j] + "' moves by up to " + num(moves) +
                   " m from its parent during a clip; it gets a free joint");
      out.dropped[j] = 0;
    } else if (out.dropped[j] > 1e-6) {
      warnings.add("bone '" + s.link_name[j] + "': the clips place it up to " +
                   num(out.dropped[j]) +
                   " m from its bind offset; a spherical joint keeps the bind offset");
    }
  }
  if (scale_error > kScaleTolerance) {
    warnings.add("the clips scale bones (largest |scale - 1| = " + num(scale_error) +
                 " after the unit scale); links are rigid, the scale is dropped");
  }
  return out;
}

namespace {

// the configuration of `model` for link poses X: per joint X_PJ⁻¹ · (pose in the parent link)
Eigen::VectorXd configuration(const Model& m,
                              const std::vector<int>& model_link,
                              const Skeleton& s,
                              const std::vector<Transform>& X) {
  Eigen::VectorXd q = core::neutral_configuration(m);
  for (std::size_t j = 0; j < s.links.size(); ++j) {
    const int i = model_link[j];
    const int iq = m.idx_q[i];
    const Transform& P = m.X_PJ[i];
    const Transform rel = j == 0 ? X[0] : X[s.parent_link[j]].inverse() * X[j];
    const Quaternion r = Quaternion(P.R.transpose() * rel.R).normalized();
    if (m.joint_type[i] == core::JointType::kFree) {
      q.segment<3>(iq) = P.R.transpose() * (rel.p - P.p);
      core::set_quaternion_at(q, iq + 3, r);
    } else {
      core::set_quaternion_at(q, iq, r);
    }
  }
  return q;
}

}  // namespace

std::vector<ImportedClip> build_clips(const Model& model,
                                      const std::vector<int>& model_link,
                                      const Skeleton& skeleton,
                                      const Motion& motion,
                                      LinkPoses& poses,
                                      double frame_rate) {
  std::vector<ImportedClip> clips;
  std::vector<Transform> X;
  double scale_error = 0;  // measured and reported by sample_motion
  for (const AnimInfo& info : motion.anims) {
    ImportedClip c;
    c.name = info.anim->mName.C_Str();
    c.start_time = info.start / info.ticks_per_second;
    c.clip.frame_time = 1.0 / frame_rate;
    for (int k = 0; k < info.frames; ++k) {
      poses.at(info, tick_of_frame(info, k, frame_rate), X, scale_error);
      c.clip.frames.push_back(configuration(model, model_link, skeleton, X));
    }
    clips.push_back(std::move(c));
  }
  return clips;
}

}  // namespace io::assimp_detail
