#include "fullarm/arm/kdl_conversion.hpp"

#include <stdexcept>

namespace fullarm::arm {
namespace {

KDL::Frame toKdl(const Eigen::Isometry3d& X) {
  const Eigen::Matrix3d R = X.linear();
  const Eigen::Vector3d p = X.translation();
  return KDL::Frame(KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)),
                    KDL::Vector(p.x(), p.y(), p.z()));
}

KDL::RigidBodyInertia toKdl(const LinkInertial& in) {
  const Eigen::Matrix3d& I = in.inertia_com_kgm2;
  // KDL's RotationalInertia takes the diagonal then xy, xz, yz entries of the matrix about
  // the centre of mass; RigidBodyInertia(m, c, Ic) shifts it to the segment frame.
  return KDL::RigidBodyInertia(in.mass_kg, KDL::Vector(in.com_m.x(), in.com_m.y(), in.com_m.z()),
                               KDL::RotationalInertia(I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)));
}

std::string parentSegment(const ArmModel& model, int parent) {
  return parent < 0 ? std::string("base") : model.joints[static_cast<std::size_t>(parent)].name;
}

}  // namespace

KDL::Tree toKdlTree(const ArmModel& model) {
  KDL::Tree tree("world");
  // addSegment refuses a name already in the tree (a joint called "base", "tool", "world" or
  // "<joint>_origin") and would leave a truncated tree: say so instead.
  const auto add = [&tree](const KDL::Segment& segment, const std::string& parent) {
    if (!tree.addSegment(segment, parent)) {
      throw std::invalid_argument("toKdlTree: cannot add segment '" + segment.getName() + "' under '" + parent +
                                  "' (world, base, tool and <joint>_origin are reserved names)");
    }
  };
  add(KDL::Segment("base", KDL::Joint("base_fixed", KDL::Joint::None), toKdl(model.X_WB)), "world");
  for (const Joint& joint : model.joints) {
    const std::string origin = joint.name + "_origin";
    add(KDL::Segment(origin, KDL::Joint(origin + "_fixed", KDL::Joint::None), toKdl(joint.X_PL0)),
        parentSegment(model, joint.parent));
    add(KDL::Segment(joint.name, KDL::Joint(joint.name, KDL::Joint::RotZ), KDL::Frame::Identity(),
                     toKdl(joint.inertial)),
        origin);
  }
  add(KDL::Segment("tool", KDL::Joint("tool_fixed", KDL::Joint::None), toKdl(model.X_LT)),
      model.joints[static_cast<std::size_t>(model.tool_link)].name);
  return tree;
}

KDL::Chain toKdlChain(const ArmModel& model, int tip_joint) {
  if (tip_joint < 0 || tip_joint >= model.numJoints()) throw std::out_of_range("toKdlChain: no such joint");
  KDL::Chain chain;
  if (!toKdlTree(model).getChain("world", model.joints[static_cast<std::size_t>(tip_joint)].name, chain)) {
    throw std::runtime_error("toKdlChain: KDL could not extract the chain");
  }
  return chain;
}

}  // namespace fullarm::arm
