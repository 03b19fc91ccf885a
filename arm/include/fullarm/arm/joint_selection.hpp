#pragma once
/// @file
/// Configuration vectors and subset vectors, and the one mapping between them.
///
/// A **configuration vector** has one entry per joint of the arm model, in ArmModel::joints
/// order (hand joints included): joint angles, g(q), the contact torques of fullarm::haptics,
/// everything fullarm::arm and fullarm::haptics compute over the whole arm.
/// A **subset vector** has one entry per joint that a subsystem drives, in that subsystem's
/// JointSelection order: the controller's joints in the gains file's order, the plant's active
/// joints. What exists only at a driven joint travels as a subset vector: load-cell readings,
/// valve and torque commands, the plant's per-joint inputs, states and measurements.
/// A subsystem that needs a configuration quantity takes the configuration vector and reads its
/// joints' entries through its JointSelection (gather); what it produces per driven joint is
/// put back into a configuration vector the same way (scatter).

#include <Eigen/Core>
#include <array>
#include <vector>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// An ordered set of distinct joints of an arm model: subset position k <-> model index
/// modelIndex(k). Fixed capacity (kMaxJoints); gather and scatter are @rt.
class JointSelection {
 public:
  /// Selects nothing (size 0).
  JointSelection() = default;
  /// The joints `model_indices` (in that order) of a configuration of `num_model_joints` joints.
  /// @throws std::invalid_argument for more than kMaxJoints joints, an index outside
  /// [0, num_model_joints) or an index listed twice.
  JointSelection(int num_model_joints, const std::vector<int>& model_indices);
  /// Every joint of a configuration of `num_model_joints` joints, in model order.
  [[nodiscard]] static JointSelection all(int num_model_joints);

  /// Number of selected joints (length of a subset vector). @rt
  [[nodiscard]] int size() const noexcept { return size_; }
  /// Length of a configuration vector. @rt
  [[nodiscard]] int numModelJoints() const noexcept { return num_model_joints_; }
  /// Model index of subset position k (0 <= k < size()). @rt
  [[nodiscard]] int modelIndex(int k) const noexcept { return index_[static_cast<std::size_t>(k)]; }
  /// Subset position of model joint `model_index`, or -1 when it is not selected. @rt
  [[nodiscard]] int position(int model_index) const noexcept;
  /// The model indices in subset order.
  [[nodiscard]] std::vector<int> modelIndices() const;

  /// subset[k] = config[modelIndex(k)] for every k. Sizes: config numModelJoints(), subset
  /// size() (checked by assert in debug builds). @rt
  void gather(const Eigen::Ref<const Eigen::VectorXd>& config, Eigen::Ref<Eigen::VectorXd> subset) const noexcept;
  /// config[modelIndex(k)] = subset[k] for every k; the other entries of config are left as
  /// they are. @rt
  void scatter(const Eigen::Ref<const Eigen::VectorXd>& subset, Eigen::Ref<Eigen::VectorXd> config) const noexcept;

 private:
  int size_ = 0;
  int num_model_joints_ = 0;
  std::array<int, kMaxJoints> index_{};
};

}  // namespace fullarm::arm
