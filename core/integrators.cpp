#include "core/integrators.hpp"

namespace core {

void configuration_rate(const Model& model,
                        const Eigen::VectorXd& q,
                        const Eigen::VectorXd& v,
                        Eigen::VectorXd& qdot) {
  qdot.setZero(model.nq);
  for (int i = 1; i < model.njoints; ++i) {
    const int iq = model.idx_q[i];
    const int iv = model.idx_v[i];
    int iquat = -1;
    switch (model.joint_type[i]) {
      case JointType::kFixed:
        break;
      case JointType::kRevolute:
      case JointType::kPrismatic:
        qdot[iq] = v[iv];
        break;
      case JointType::kSpherical:
        iquat = iq;
        break;
      case JointType::kFree: {
        const Quaternion r = quaternion_at(q, iq + 3);
        // the stage quaternion may be slightly off unit length: rotate with its normalized form
        qdot.segment<3>(iq) = r.normalized() * Vector3(v.segment<3>(iv + 3));
        iquat = iq + 3;
        break;
      }
    }
    if (iquat >= 0) {
      // q̇ = ½ q ⊗ (0, ω)
      const Quaternion r = quaternion_at(q, iquat);
      const Quaternion w(0.0, v[iv], v[iv + 1], v[iv + 2]);
      const Quaternion d = r * w;
      set_quaternion_at(qdot, iquat,
                        Quaternion(0.5 * d.w(), 0.5 * d.x(), 0.5 * d.y(), 0.5 * d.z()));
    }
  }
}

}  // namespace core
