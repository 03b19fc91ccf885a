#include "fullarm/arm/joint_selection.hpp"

#include <algorithm>
#include <cassert>
#include <stdexcept>
#include <string>

namespace fullarm::arm {

JointSelection::JointSelection(int num_model_joints, const std::vector<int>& model_indices)
    : size_(static_cast<int>(model_indices.size())), num_model_joints_(num_model_joints) {
  if (model_indices.size() > static_cast<std::size_t>(kMaxJoints)) {
    throw std::invalid_argument("JointSelection: " + std::to_string(model_indices.size()) +
                                " joints, expected at most " + std::to_string(kMaxJoints));
  }
  for (std::size_t k = 0; k < model_indices.size(); ++k) {
    const int i = model_indices[k];
    if (i < 0 || i >= num_model_joints) {
      throw std::invalid_argument("JointSelection: joint index " + std::to_string(i) + " outside [0, " +
                                  std::to_string(num_model_joints) + ")");
    }
    if (std::find(model_indices.begin(), model_indices.begin() + static_cast<std::ptrdiff_t>(k), i) !=
        model_indices.begin() + static_cast<std::ptrdiff_t>(k)) {
      throw std::invalid_argument("JointSelection: joint index " + std::to_string(i) + " listed twice");
    }
    index_[k] = i;
  }
}

JointSelection JointSelection::all(int num_model_joints) {
  std::vector<int> indices(static_cast<std::size_t>(std::max(num_model_joints, 0)));
  for (int i = 0; i < num_model_joints; ++i) indices[static_cast<std::size_t>(i)] = i;
  return JointSelection(num_model_joints, indices);
}

int JointSelection::position(int model_index) const noexcept {
  for (int k = 0; k < size_; ++k) {
    if (index_[static_cast<std::size_t>(k)] == model_index) return k;
  }
  return -1;
}

std::vector<int> JointSelection::modelIndices() const {
  return {index_.begin(), index_.begin() + size_};
}

void JointSelection::gather(const Eigen::Ref<const Eigen::VectorXd>& config,
                            Eigen::Ref<Eigen::VectorXd> subset) const noexcept {
  assert(config.size() == num_model_joints_ && subset.size() == size_);
  for (int k = 0; k < size_; ++k) subset[k] = config[index_[static_cast<std::size_t>(k)]];
}

void JointSelection::scatter(const Eigen::Ref<const Eigen::VectorXd>& subset,
                             Eigen::Ref<Eigen::VectorXd> config) const noexcept {
  assert(config.size() == num_model_joints_ && subset.size() == size_);
  for (int k = 0; k < size_; ++k) config[index_[static_cast<std::size_t>(k)]] = subset[k];
}

}  // namespace fullarm::arm
