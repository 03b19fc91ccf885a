#include "fullarm/haptics/contact_forces.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/core/yaml_reader.hpp"

namespace fullarm::haptics {

using Eigen::Vector3d;

namespace {

void require(bool ok, const std::filesystem::path& file, const char* key, const std::string& message) {
  if (!ok) throw core::ConfigError(file, key, message);
}

}  // namespace

// §3.2.1: the look-ahead check L - d_f >= v_max x latency (reports/equations.md).
void validateHapticsParams(const HapticsParams& p, const std::filesystem::path& file) {
  require(p.stiffness_npm > 0.0 && std::isfinite(p.stiffness_npm), file, "contact.stiffness_npm",
          "expected a finite stiffness > 0 N/m");
  require(p.damping_nspm >= 0.0 && std::isfinite(p.damping_nspm), file, "contact.damping_nspm",
          "expected a finite damping >= 0 N s/m");
  require(p.force_threshold_m > 0.0 && std::isfinite(p.force_threshold_m), file, "contact.force_threshold_m",
          "expected a finite force threshold d_f > 0 m");
  require(p.cutoff_m > p.force_threshold_m && std::isfinite(p.cutoff_m), file, "contact.cutoff_m",
          "expected a finite cutoff L greater than force_threshold_m (the global search must look ahead)");
  require(p.prune_radius_m >= 0.0 && std::isfinite(p.prune_radius_m), file, "contact.prune_radius_m",
          "expected a finite pruning radius >= 0 m");
  require(p.patch_radius_m > 0.0 && std::isfinite(p.patch_radius_m), file, "contact.patch_radius_m",
          "expected a finite patch radius > 0 m");
  require(p.max_force_per_minimum_n > 0.0 && std::isfinite(p.max_force_per_minimum_n), file,
          "contact.max_force_per_minimum_n", "expected a finite force limit > 0 N");
  require(p.descent.max_iterations >= 1 && p.descent.max_iterations <= 1000, file, "local_descent.max_iterations",
          "expected an integer in [1, 1000]");
  require(p.descent.min_decrease_m >= 0.0 && std::isfinite(p.descent.min_decrease_m), file,
          "local_descent.min_decrease_m", "expected a finite value >= 0 m");
  require(p.descent.drop_beyond_m > 0.0, file, "local_descent.drop_beyond_m", "expected a value > 0 m");
  require(p.search_latency_p99_ms > 0.0 && std::isfinite(p.search_latency_p99_ms), file,
          "global_search.latency_p99_ms", "expected a finite latency > 0 ms");
  require(p.max_link_speed_mps > 0.0 && std::isfinite(p.max_link_speed_mps), file, "global_search.max_link_speed_mps",
          "expected a finite speed > 0 m/s");
  // §3.2.1: the look-ahead must cover the distance a link travels while its new minima are on
  // their way: L - d_f >= v_max x latency.
  const double margin_m = p.cutoff_m - p.force_threshold_m;
  const double needed_m = minimumCutoffMargin(p);
  if (!(margin_m >= needed_m)) {
    std::ostringstream text;
    text.precision(3);
    text << "the look-ahead L - d_f = " << 1e3 * margin_m << " mm (cutoff_m " << p.cutoff_m << " - force_threshold_m "
         << p.force_threshold_m << ") is shorter than the distance a link covers before the global search's minima "
         << "arrive: max_link_speed_mps " << p.max_link_speed_mps << " m/s x latency_p99_ms "
         << p.search_latency_p99_ms << " ms = " << 1e3 * needed_m
         << " mm (global_search); raise cutoff_m to at least " << p.force_threshold_m + needed_m
         << " m, or measure a shorter latency";
    throw core::ConfigError(file, "contact.cutoff_m", text.str());
  }
}

// §3.2.1: the smallest safe look-ahead (reports/equations.md).
double minimumCutoffMargin(const HapticsParams& params) noexcept {
  return params.max_link_speed_mps * 1e-3 * params.search_latency_p99_ms;
}

namespace {

HapticsParams readHapticsParams(const core::YamlMap& root) {
  const std::filesystem::path& file = root.file();
  HapticsParams p;
  const std::string mode = root.string("mode");
  if (mode == "full_arm") {
    p.mode = RenderMode::kFullArm;
  } else if (mode == "hand_only") {
    p.mode = RenderMode::kHandOnly;
  } else {
    root.fail("mode", "expected full_arm or hand_only, got '" + mode + "'");
  }
  const core::YamlMap c = root.map("contact");
  p.stiffness_npm = c.number("stiffness_npm", "N/m");
  p.damping_nspm = c.number("damping_nspm", "N s/m");
  p.force_threshold_m = c.number("force_threshold_m", "metres");
  p.cutoff_m = c.number("cutoff_m", "metres");
  p.prune_radius_m = c.number("prune_radius_m", "metres");
  const std::string norm = c.string("normalise_per_patch");
  if (norm != "true" && norm != "false") c.fail("normalise_per_patch", "expected true or false, got '" + norm + "'");
  p.normalise_per_patch = norm == "true";
  p.patch_radius_m = c.number("patch_radius_m", "metres");
  p.max_force_per_minimum_n = c.number("max_force_per_minimum_n", "N");
  c.finish();
  const core::YamlMap d = root.map("local_descent");
  p.descent.max_iterations = d.integer("max_iterations");
  p.descent.min_decrease_m = d.number("min_decrease_m", "metres");
  if (const auto drop = d.optionalNumber("drop_beyond_m", "metres")) p.descent.drop_beyond_m = *drop;
  d.finish();
  if (root.has("global_search")) {
    const core::YamlMap g = root.map("global_search");
    p.search_latency_p99_ms = g.number("latency_p99_ms", "milliseconds");
    p.max_link_speed_mps = g.number("max_link_speed_mps", "m/s");
    g.finish();
  }
  root.finish();
  validateHapticsParams(p, file);
  return p;
}

}  // namespace

HapticsParams parseHapticsParams(std::string_view yaml_text, const std::filesystem::path& file) {
  return readHapticsParams(core::YamlMap::parse(yaml_text, file));
}

std::filesystem::path defaultHapticsParamsPath() {
  return core::defaultConfigPath("haptics.yaml");
}

HapticsParams loadHapticsParams(const std::filesystem::path& file) {
  return readHapticsParams(core::YamlMap::load(file));
}

ContactData::ContactData(const arm::ArmModel& model, int max_minima)
    : f_W(static_cast<std::size_t>(max_minima), Vector3d::Zero()),
      p_W(static_cast<std::size_t>(max_minima), Vector3d::Zero()),
      stiffness_npm(static_cast<std::size_t>(max_minima), 0.0),
      rendered(static_cast<std::size_t>(max_minima), 0),
      magnitude_n(static_cast<std::size_t>(max_minima), 0.0),
      patch_root(static_cast<std::size_t>(max_minima), 0),
      patch_weight(static_cast<std::size_t>(max_minima), 0.0),
      tau_contact_nm(Eigen::VectorXd::Zero(model.numJoints())),
      links(static_cast<std::size_t>(model.numJoints())),
      link_force_W(static_cast<std::size_t>(model.numJoints()), Vector3d::Zero()),
      link_moment_W(static_cast<std::size_t>(model.numJoints()), Vector3d::Zero()) {}

bool isHandLink(const arm::ArmModel& model, int link) noexcept {
  return link == model.tool_link || model.joints[static_cast<std::size_t>(link)].is_hand;
}

void resetContactRecords(ContactData& data) noexcept {
  for (auto& r : data.links) r = LinkContactRecord{};
}

// §3.2.2: contact spring on each minimum below the force threshold (reports/equations.md).
void computeContactForces(const HapticsParams& params, const arm::ArmModel& model, const arm::ArmData& fk,
                          std::span<const LocalMinimum> minima, double dt_s, ContactData& data) noexcept {
  const std::size_t m = minima.size();
  data.status.clear();
  data.active_springs = 0;
  const int n_links = model.numJoints();
  if (m > data.f_W.size()) {
    data.status.raise(core::RtCode::kBadInput, core::kFaultCapacity, "more minima than the contact capacity");
    return;
  }
  if (!(dt_s > 0.0)) {
    data.status.raise(core::RtCode::kBadInput, core::kFaultOutOfRange, "non-positive tick period");
    return;
  }
  // Per-link tick state.
  for (auto& r : data.links) {
    r.min_distance_m = std::numeric_limits<double>::infinity();
    r.depth_m = 0.0;
  }
  const double df = params.force_threshold_m;
  for (std::size_t i = 0; i < m; ++i) {
    const LocalMinimum& mi = minima[i];
    data.f_W[i].setZero();
    data.rendered[i] = 0;
    data.stiffness_npm[i] = 0.0;
    if (mi.link < 0 || mi.link >= n_links) {
      data.status.raise(core::RtCode::kBadInput, core::kFaultBadIndex, "minimum on a link index out of range");
      continue;
    }
    if (!std::isfinite(mi.distance_m) || !mi.p_L.allFinite() || !mi.u_W.allFinite()) {
      data.status.raise(core::RtCode::kBadInput, core::kFaultNonFiniteInput, "non-finite minimum");
      continue;
    }
    data.p_W[i] = fk.X_WL[static_cast<std::size_t>(mi.link)] * mi.p_L;
    LinkContactRecord& rec = data.links[static_cast<std::size_t>(mi.link)];
    rec.min_distance_m = std::min(rec.min_distance_m, mi.distance_m);
    if (mi.distance_m >= df) continue;
    if (params.mode == RenderMode::kHandOnly && !isHandLink(model, mi.link)) continue;
    // Spring law: |f| = k (d_f - d) - b d_dot, pushing the link away from the object.
    double magnitude = params.stiffness_npm * (df - mi.distance_m);
    if (params.damping_nspm > 0.0 && std::isfinite(mi.previous_distance_m)) {
      magnitude -= params.damping_nspm * (mi.distance_m - mi.previous_distance_m) / dt_s;
    }
    data.magnitude_n[i] = magnitude;
    data.stiffness_npm[i] = params.stiffness_npm;
    data.rendered[i] = 1;
  }
  // Optional per-patch normalisation: minima of one link/object pair whose link points are
  // chained within patch_radius_m form a patch; each spring is scaled by its share
  // (d_f - d_i) / sum_patch (d_f - d_j), so a patch renders like one spring whatever the number
  // of minima on it, and a minimum entering or leaving at d_f (weight 0) changes nothing.
  if (params.normalise_per_patch) {
    auto root = [&data](int i) {
      while (data.patch_root[static_cast<std::size_t>(i)] != i) i = data.patch_root[static_cast<std::size_t>(i)];
      return i;
    };
    for (std::size_t i = 0; i < m; ++i) {
      data.patch_root[i] = static_cast<int>(i);
      data.patch_weight[i] = 0.0;
    }
    const double r2 = params.patch_radius_m * params.patch_radius_m;
    for (std::size_t i = 0; i < m; ++i) {
      if (data.rendered[i] == 0) continue;
      for (std::size_t j = 0; j < i; ++j) {
        if (data.rendered[j] == 0 || minima[j].link != minima[i].link || minima[j].object != minima[i].object ||
            (minima[j].p_L - minima[i].p_L).squaredNorm() > r2) {
          continue;
        }
        const int a = root(static_cast<int>(i));
        const int b = root(static_cast<int>(j));
        if (a != b) data.patch_root[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
      }
    }
    for (std::size_t i = 0; i < m; ++i) {
      if (data.rendered[i] != 0)
        data.patch_weight[static_cast<std::size_t>(root(static_cast<int>(i)))] += df - minima[i].distance_m;
    }
    for (std::size_t i = 0; i < m; ++i) {
      if (data.rendered[i] == 0) continue;
      const double total = data.patch_weight[static_cast<std::size_t>(root(static_cast<int>(i)))];
      const double share = total > 0.0 ? (df - minima[i].distance_m) / total : 1.0;
      data.magnitude_n[i] *= share;
      data.stiffness_npm[i] *= share;
    }
  }
  for (std::size_t i = 0; i < m; ++i) {
    if (data.rendered[i] == 0) continue;
    const double magnitude = std::clamp(data.magnitude_n[i], 0.0, params.max_force_per_minimum_n);
    data.f_W[i] = -magnitude * minima[i].u_W;
    ++data.active_springs;
  }
  // Contact records: in contact = inside the force layer; penetrating = touching/intersecting.
  for (auto& r : data.links) {
    const bool contact = r.min_distance_m < df;
    const bool penetrating = r.min_distance_m <= 0.0;
    if (contact) {
      if (!r.in_contact) {
        ++r.contact_onsets;
        r.contact_duration_s = 0.0;
      }
      r.contact_duration_s += dt_s;
      r.total_contact_s += dt_s;
      r.depth_m = df - r.min_distance_m;
      r.max_depth_m = std::max(r.max_depth_m, r.depth_m);
    } else {
      r.contact_duration_s = 0.0;
    }
    if (penetrating) r.total_penetration_s += dt_s;
    r.in_contact = contact;
    r.penetrating = penetrating;
  }
}

// Eq. (1): tailored force Jacobian of the joints that move the contact link; Eq. (2): torque of the contact link's own
// joint (reports/equations.md).
void addTailoredJacobianTorques(const arm::ArmModel& model, const arm::ArmData& fk, int link, const Vector3d& p_W,
                                const Vector3d& f_W, Eigen::Ref<Eigen::VectorXd> tau) noexcept {
  // The contact force moved to the contact link's joint origin o_n: force f_c, moment eta_c.
  const Vector3d eta_c = (p_W - fk.o_W[static_cast<std::size_t>(link)]).cross(f_W);
  addTailoredJacobianWrench(model, fk, link, f_W, eta_c, tau);
}

void addTailoredJacobianWrench(const arm::ArmModel& model, const arm::ArmData& fk, int link, const Vector3d& f_W,
                               const Vector3d& eta_c, Eigen::Ref<Eigen::VectorXd> tau) noexcept {
  const auto n = static_cast<std::size_t>(link);
  const Vector3d& o_n = fk.o_W[n];
  // Eq. (2) of the DTS paper: tau_n = z_n . eta_c.
  tau[link] += fk.z_W[n].dot(eta_c);
  // Eq. (1) of the DTS paper: the tailored force Jacobian rows (z_i x b_i)^T, z_i^T of the
  // joints proximal to the contact link, b_i = o_n - o_i.
  for (int i = model.joints[n].parent; i >= 0; i = model.joints[static_cast<std::size_t>(i)].parent) {
    const auto k = static_cast<std::size_t>(i);
    const Vector3d b_i = o_n - fk.o_W[k];
    tau[i] += fk.z_W[k].cross(b_i).dot(f_W) + fk.z_W[k].dot(eta_c);
  }
}

void computeContactTorques(const arm::ArmModel& model, const arm::ArmData& fk, std::span<const LocalMinimum> minima,
                           ContactData& data) noexcept {
  data.tau_contact_nm.setZero();
  if (data.status.ok()) {
    // Eq. (1)-(2) are linear in (f_c, eta_c): the minima of one link are summed into one force
    // at that link's joint origin and one moment about it, then mapped once per link.
    for (auto& f : data.link_force_W) f.setZero();
    for (auto& h : data.link_moment_W) h.setZero();
    for (std::size_t i = 0; i < minima.size() && i < data.f_W.size(); ++i) {
      if (data.rendered[i] == 0) continue;
      const auto n = static_cast<std::size_t>(minima[i].link);
      data.link_force_W[n] += data.f_W[i];
      data.link_moment_W[n] += (data.p_W[i] - fk.o_W[n]).cross(data.f_W[i]);
    }
    for (int n = 0; n < model.numJoints(); ++n) {
      const auto k = static_cast<std::size_t>(n);
      if (data.link_force_W[k].squaredNorm() == 0.0 && data.link_moment_W[k].squaredNorm() == 0.0) continue;
      addTailoredJacobianWrench(model, fk, n, data.link_force_W[k], data.link_moment_W[k], data.tau_contact_nm);
    }
  }
}

}  // namespace fullarm::haptics
