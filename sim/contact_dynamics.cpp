#include "sim/contact_dynamics.hpp"

#include <algorithm>
#include <tuple>

namespace sim {

namespace {
auto pair_of(const FeatureKey& k) {
  return std::make_tuple(k.body, k.link, k.partner_body, k.partner_link,
                         k.partner_body < 0 ? k.env : 0);
}
}  // namespace

void group_into_pairs(std::vector<ContactPoint>& points, std::vector<ContactPair>& pairs) {
  pairs.clear();
  std::stable_sort(points.begin(), points.end(), [](const ContactPoint& a, const ContactPoint& b) {
    return pair_of(a.key) < pair_of(b.key);
  });
  for (int k = 0; k < static_cast<int>(points.size()); ++k) {
    const FeatureKey& key = points[k].key;
    if (pairs.empty() || pair_of(points[pairs.back().first_point].key) != pair_of(key)) {
      ContactPair p;
      p.body = key.body;
      p.link = key.link;
      p.partner_body = key.partner_body;
      p.partner_link = key.partner_link;
      p.first_point = k;
      pairs.push_back(p);
    }
    ContactPair& p = pairs.back();
    ++p.point_count;
    p.ref_W += points[k].p_W;
    p.normal_W += points[k].n_W;
  }
  for (ContactPair& p : pairs) {
    p.ref_W /= static_cast<double>(p.point_count);
    const double n = p.normal_W.norm();
    if (n > 0) p.normal_W /= n;
  }
}

void solve_implicit_wrenches(std::vector<ContactPair>& pairs,
                             const Eigen::MatrixXd& Phi,
                             const Eigen::VectorXd& free_acceleration,
                             double h,
                             ImplicitWorkspace& ws) {
  const int m = 6 * static_cast<int>(pairs.size());
  Eigen::MatrixXd& A = ws.A;
  Eigen::VectorXd& rhs = ws.rhs;
  if (A.rows() != m) {
    A.resize(m, m);
    rhs.resize(m);
    ws.x.resize(m);
    ws.lu = Eigen::PartialPivLU<Eigen::MatrixXd>(m);
  }
  const int np = static_cast<int>(pairs.size());
  ws.released.assign(np, 0);
  // at most one round per pair: each round lets go of at least one
  for (int round = 0; round <= np; ++round) {
    // A = E − h (D + h K) Φ, block row by block row (K and D are per pair); a released pair's
    // row is τ̂ = 0
    A.setIdentity();
    for (int i = 0; i < np; ++i) {
      const ContactPair& p = pairs[i];
      if (ws.released[i]) {
        rhs.segment<6>(6 * i).setZero();
        continue;
      }
      const Matrix6 C = h * (p.D + h * p.K);
      A.middleRows<6>(6 * i).noalias() -= C * Phi.middleRows<6>(6 * i);
      rhs.segment<6>(6 * i) =
          p.wrench0 + h * (p.K * p.velocity) + C * free_acceleration.segment<6>(6 * i);
    }
    ws.lu.compute(A);
    ws.x = ws.lu.solve(rhs);
    bool pulls = false;
    for (int i = 0; i < np; ++i) {
      if (!ws.released[i] && ws.x.segment<3>(6 * i + 3).dot(pairs[i].normal_W) < 0) {
        ws.released[i] = 1;
        pulls = true;
      }
    }
    if (!pulls) break;
  }
  for (int i = 0; i < np; ++i) pairs[i].wrench = ws.x.segment<6>(6 * i);
}

}  // namespace sim
