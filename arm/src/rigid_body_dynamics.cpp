#include "fullarm/arm/rigid_body_dynamics.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace fullarm::arm {

namespace {

// Spatial algebra at the world origin (Featherstone 2008, sec. 2.9-2.13), on 3-vector pairs.
// Motion cross product: (w, v) x (w', v') = (w x w', w x v' + v x w').
[[gnu::always_inline]] inline SpatialVector crossMotion(const SpatialVector& a, const SpatialVector& b) noexcept {
  return {a.top.cross(b.top), a.top.cross(b.bottom) + a.bottom.cross(b.top)};
}
// Force cross product: (w, v) x* (n, f) = (w x n + v x f, w x f).
[[gnu::always_inline]] inline SpatialVector crossForce(const SpatialVector& a, const SpatialVector& f) noexcept {
  return {a.top.cross(f.top) + a.bottom.cross(f.bottom), a.top.cross(f.bottom)};
}
// Spatial inertia (mass m, first moment h = m c, rotational inertia I_O about the origin)
// applied to a motion: (I_O w + h x v, m v - h x w).
[[gnu::always_inline]] inline SpatialVector applyInertia(double m, const Eigen::Vector3d& h,
                                                         const Eigen::Matrix3d& inertia_O,
                                                         const SpatialVector& v) noexcept {
  return {inertia_O * v.top + h.cross(v.bottom), m * v.bottom - h.cross(v.top)};
}
[[gnu::always_inline]] inline SpatialVector operator+(const SpatialVector& a, const SpatialVector& b) noexcept {
  return {a.top + b.top, a.bottom + b.bottom};
}
[[gnu::always_inline]] inline SpatialVector operator-(const SpatialVector& a, const SpatialVector& b) noexcept {
  return {a.top - b.top, a.bottom - b.bottom};
}
[[gnu::always_inline]] inline SpatialVector& operator+=(SpatialVector& a, const SpatialVector& b) noexcept {
  a.top += b.top;
  a.bottom += b.bottom;
  return a;
}
[[gnu::always_inline]] inline SpatialVector scaled(const SpatialVector& a, double k) noexcept {
  return {k * a.top, k * a.bottom};
}
// Power pairing of a motion and a force.
[[gnu::always_inline]] inline double dot(const SpatialVector& motion, const SpatialVector& force) noexcept {
  return motion.top.dot(force.top) + motion.bottom.dot(force.bottom);
}

Eigen::Matrix3d skewSquare(const Eigen::Vector3d& c) {
  return c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose();
}

}  // namespace

void computeRigidBodyKinematics(const RigidBodyModel& model, RigidBodyData& data, const BodyVector& q,
                                const BodyVector& qd) noexcept {
  data.ground_accel = {Eigen::Vector3d::Zero(), -model.gravity_W_mps2};
  for (int o = 0; o < model.tree.n; ++o) {
    const int b = model.tree.order[static_cast<std::size_t>(o)];
    const auto k = static_cast<std::size_t>(b);
    const int p = model.tree.parent[k];
    Eigen::Matrix3d R0;
    Eigen::Vector3d o_W;
    if (p < 0) {
      R0 = model.rotation0[k];
      o_W = model.translation0_m[k];
    } else {
      const auto pk = static_cast<std::size_t>(p);
      R0.noalias() = data.R_WB[pk] * model.rotation0[k];
      o_W = data.o_W[pk] + data.R_WB[pk] * model.translation0_m[k];
    }
    // R_WB = R0 Rz(q): one sincos per joint.
    const double c = std::cos(q[b]);
    const double s = std::sin(q[b]);
    data.cos_q[k] = c;
    data.sin_q[k] = s;
    Eigen::Matrix3d& R = data.R_WB[k];
    R.col(0) = c * R0.col(0) + s * R0.col(1);
    R.col(1) = c * R0.col(1) - s * R0.col(0);
    R.col(2) = R0.col(2);
    data.o_W[k] = o_W;
    const Eigen::Vector3d z = R.col(2);
    data.s[k] = {z, o_W.cross(z)};
    data.qd[k] = qd[b];
    data.V[k] = scaled(data.s[k], qd[b]);
    if (p >= 0) data.V[k] += data.V[static_cast<std::size_t>(p)];
    // Spatial inertia about the world origin (R2).
    const double m = model.mass_kg[k];
    const Eigen::Vector3d com = o_W + R * model.com_m[k];
    data.mass_kg[k] = m;
    data.first_moment_kgm[k] = m * com;
    data.inertia_O_kgm2[k].noalias() = R * model.inertia_com_kgm2[k] * R.transpose();
    data.inertia_O_kgm2[k] += m * skewSquare(com);
  }
}

namespace {

[[gnu::always_inline]] inline SpatialVector inertiaTimes(const RigidBodyData& data, std::size_t k,
                                                         const SpatialVector& v) noexcept {
  return applyInertia(data.mass_kg[k], data.first_moment_kgm[k], data.inertia_O_kgm2[k], v);
}

// Newton-Euler at qdd over the current kinematics: A, F, F_tot and tau (R1-R4).
void newtonEulerPass(const RigidBodyTree& tree, RigidBodyData& data, const BodyVector& qdd, BodyVector& tau) noexcept {
  tau.resize(tree.n);  // within the fixed capacity: no allocation
  const SpatialVector& ground_accel = data.ground_accel;
  for (int o = 0; o < tree.n; ++o) {
    const int b = tree.order[static_cast<std::size_t>(o)];
    const auto k = static_cast<std::size_t>(b);
    const int p = tree.parent[k];
    const SpatialVector& A_p = p < 0 ? ground_accel : data.A[static_cast<std::size_t>(p)];
    // A_b = A_p + s qdd + V_b x s qd (the axis is fixed in the parent: s' = V_p x s = V_b x s).
    data.A[k] = A_p + scaled(data.s[k], qdd[b]) + scaled(crossMotion(data.V[k], data.s[k]), data.qd[k]);
    data.IV[k] = inertiaTimes(data, k, data.V[k]);
    data.IA[k] = inertiaTimes(data, k, data.A[k]);
    data.F[k] = data.IA[k] + crossForce(data.V[k], data.IV[k]);
    data.F_tot[k] = data.F[k];
  }
  for (int o = tree.n - 1; o >= 0; --o) {
    const int b = tree.order[static_cast<std::size_t>(o)];
    const auto k = static_cast<std::size_t>(b);
    tau[b] = dot(data.s[k], data.F_tot[k]);
    const int p = tree.parent[k];
    if (p >= 0) data.F_tot[static_cast<std::size_t>(p)] += data.F_tot[k];
  }
}

}  // namespace

// R3: Newton-Euler outward pass; R4: joint torques from the subtree forces (reports/equations.md).
void computeRigidBodyInverseDynamics(const RigidBodyTree& tree, RigidBodyData& data, const BodyVector& qdd,
                                     BodyVector& tau) noexcept {
  newtonEulerPass(tree, data, qdd, tau);
}

// D2: gravity torques g(q) = ID(q, 0, 0) (reports/equations.md).
void computeRigidBodyGravity(const RigidBodyTree& tree, const RigidBodyData& data, BodyVector& tau) noexcept {
  tau.resize(tree.n);  // within the fixed capacity: no allocation
  // Body force at rest: I (0, a) = (h x a, m a) with a = -g, the ground's acceleration.
  const Eigen::Vector3d& a = data.ground_accel.bottom;
  std::array<SpatialVector, kMaxBodies> f{};
  for (int b = 0; b < tree.n; ++b) {
    const auto k = static_cast<std::size_t>(b);
    f[k] = {data.first_moment_kgm[k].cross(a), data.mass_kg[k] * a};
  }
  for (int o = tree.n - 1; o >= 0; --o) {
    const int b = tree.order[static_cast<std::size_t>(o)];
    const auto k = static_cast<std::size_t>(b);
    tau[b] = dot(data.s[k], f[k]);
    const int p = tree.parent[k];
    if (p >= 0) f[static_cast<std::size_t>(p)] += f[k];
  }
}

// R5: composite rigid bodies (mass matrix) (reports/equations.md).
void computeRigidBodyMassMatrix(const RigidBodyTree& tree, const RigidBodyData& data, BodyMatrix& mass) noexcept {
  const int n = tree.n;
  mass.setZero(n, n);
  // Composite inertias I^C_b = sum over the subtree (additive at the world origin).
  std::array<double, kMaxBodies> m{};
  std::array<Eigen::Vector3d, kMaxBodies> h{};
  std::array<Eigen::Matrix3d, kMaxBodies> inertia{};
  for (int b = 0; b < n; ++b) {
    const auto k = static_cast<std::size_t>(b);
    m[k] = data.mass_kg[k];
    h[k] = data.first_moment_kgm[k];
    inertia[k] = data.inertia_O_kgm2[k];
  }
  for (int o = n - 1; o >= 0; --o) {
    const auto k = static_cast<std::size_t>(tree.order[static_cast<std::size_t>(o)]);
    const int p = tree.parent[k];
    if (p < 0) continue;
    const auto pk = static_cast<std::size_t>(p);
    m[pk] += m[k];
    h[pk] += h[k];
    inertia[pk] += inertia[k];
  }
  for (int j = 0; j < n; ++j) {
    const auto kj = static_cast<std::size_t>(j);
    const SpatialVector Y = applyInertia(m[kj], h[kj], inertia[kj], data.s[kj]);
    for (int i = j; i >= 0; i = tree.parent[static_cast<std::size_t>(i)]) {
      const double value = dot(data.s[static_cast<std::size_t>(i)], Y);
      mass(i, j) = value;
      mass(j, i) = value;
    }
  }
}

void computeRigidBodyInverseDynamicsDerivativesPerBody(const RigidBodyTree& tree, RigidBodyData& data,
                                                       const BodyVector& qdd, BodyVector& tau, BodyMatrix& dtau_dq,
                                                       BodyMatrix& dtau_dqd) noexcept {
  const int n = tree.n;
  computeRigidBodyInverseDynamics(tree, data, qdd, tau);
  dtau_dq.setZero(n, n);
  dtau_dqd.setZero(n, n);
  const SpatialVector& ground_accel = data.ground_accel;
  const SpatialVector zero{};
  std::array<SpatialVector, kMaxBodies> dq_sum{};
  std::array<SpatialVector, kMaxBodies> dqd_sum{};
  for (int j = 0; j < n; ++j) {
    const auto kj = static_cast<std::size_t>(j);
    const int pj = tree.parent[kj];
    const SpatialVector& s = data.s[kj];
    const SpatialVector& V_p = pj < 0 ? zero : data.V[static_cast<std::size_t>(pj)];
    const SpatialVector& A_p = pj < 0 ? ground_accel : data.A[static_cast<std::size_t>(pj)];
    // Per-joint constants: w = V_p x s, t = s x V_p, u = -s x A_p - w x V_p.
    const SpatialVector w = crossMotion(V_p, s);
    const SpatialVector t = crossMotion(s, V_p);
    const SpatialVector u = scaled(crossMotion(s, A_p) + crossMotion(w, V_p), -1.0);
    // Per body k moved by joint j: d F_k / d q_j and d F_k / d qd_j (R7, R8). Turning the
    // subtree about s gives dV = s x (V - V_p), dA = s x (A - A_p) + w x (V - V_p) and
    // d(I) X = s x* (I X) - I (s x X); collected:
    //   dF/dq  = s x* (I A) + I (u + w x V) + (s x V - t) x* (I V) + V x* (s x* (I V) - I t)
    //   dF/dqd = I (w + s x V - t) + s x* (I V) + V x* (I s)
    for (int b = 0; b < n; ++b) {
      const auto k = static_cast<std::size_t>(b);
      if (!tree.supports[kj][k]) {
        dq_sum[k] = zero;
        dqd_sum[k] = zero;
        continue;
      }
      const SpatialVector& V = data.V[k];
      const SpatialVector& IV = data.IV[k];
      const SpatialVector s_x_V = crossMotion(s, V);
      const SpatialVector s_x_IV = crossForce(s, IV);
      dq_sum[k] = crossForce(s, data.IA[k]) + inertiaTimes(data, k, u + crossMotion(w, V)) + crossForce(s_x_V - t, IV) +
                  crossForce(V, s_x_IV - inertiaTimes(data, k, t));
      dqd_sum[k] = inertiaTimes(data, k, w + s_x_V - t) + s_x_IV + crossForce(V, inertiaTimes(data, k, s));
    }
    // Subtree sums: joint i sees the bodies of its subtree that joint j moves.
    for (int o = n - 1; o >= 0; --o) {
      const auto k = static_cast<std::size_t>(tree.order[static_cast<std::size_t>(o)]);
      const int p = tree.parent[k];
      if (p < 0) continue;
      dq_sum[static_cast<std::size_t>(p)] += dq_sum[k];
      dqd_sum[static_cast<std::size_t>(p)] += dqd_sum[k];
    }
    // tau_i = s_i . F_tot_i; s_i itself turns with q_j when joint j moves body i (R6).
    for (int i = 0; i < n; ++i) {
      const auto ki = static_cast<std::size_t>(i);
      double dq = dot(data.s[ki], dq_sum[ki]);
      if (tree.supports[kj][ki] && i != j) dq += dot(crossMotion(s, data.s[ki]), data.F_tot[ki]);
      dtau_dq(i, j) = dq;
      dtau_dqd(i, j) = dot(data.s[ki], dqd_sum[ki]);
    }
  }
}

namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

[[gnu::always_inline]] inline Eigen::Matrix3d skew(const Eigen::Vector3d& a) noexcept {
  Eigen::Matrix3d m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}
[[gnu::always_inline]] inline Vector6 stacked(const SpatialVector& a) noexcept {
  Vector6 v;
  v << a.top, a.bottom;
  return v;
}
[[gnu::always_inline]] inline SpatialVector split(const Vector6& v) noexcept {
  return {v.head<3>(), v.tail<3>()};
}

}  // namespace

void computeRigidBodyInverseDynamicsDerivatives(const RigidBodyTree& tree, RigidBodyData& data, const BodyVector& qdd,
                                                BodyVector& tau, BodyMatrix& dtau_dq, BodyMatrix& dtau_dqd) noexcept {
  // R13 (reports/equations.md): the per-body sums of computeRigidBodyInverseDynamicsDerivativesPerBody (R7, R8)
  // collected into composite quantities of each subtree c, so that every (i, j) entry is a dot product. With the Jacobi
  // identity (s x V) x* f + V x* (s x* f) = s x* (V x* f):
  //   sum_{k in c} dF_k/dq_j  = s x* F_tot_c + I^C_c u - B_c w + w x* (IV)^C_c
  //   sum_{k in c} dF_k/dqd_j = 2 I^C_c w - B_c s + s x* (IV)^C_c
  // with s, w = V_p x s, u = -(s x A_p + w x V_p) of joint j, I^C the composite inertia, (IV)^C the composite momentum
  // and B_c = sum_k (I_k crm(V_k) + crm(V_k)^T I_k) (symmetric). For i an ancestor of (or equal to) j the subtree is
  // j's: dtau_i/dq_j = s_i . D_j. For i a descendant of j it is i's, the turning of s_i cancels s x* F_tot_i, and
  // dtau_i/dq_j = u . (I^C_i s_i) + w . b_i, dtau_i/dqd_j = 2 w . (I^C_i s_i) + s . b_i, b_i = -B_i s_i - s_i x*
  // (IV)^C_i.
  const int n = tree.n;
  computeRigidBodyInverseDynamics(tree, data, qdd, tau);
  dtau_dq.setZero(n, n);
  dtau_dqd.setZero(n, n);
  std::array<double, kMaxBodies> mass_c{};
  std::array<Eigen::Vector3d, kMaxBodies> moment_c{};
  std::array<Eigen::Matrix3d, kMaxBodies> inertia_c{};
  std::array<SpatialVector, kMaxBodies> momentum_c{};
  std::array<Matrix6, kMaxBodies> b_c{};
  for (int b = 0; b < n; ++b) {
    const auto k = static_cast<std::size_t>(b);
    mass_c[k] = data.mass_kg[k];
    moment_c[k] = data.first_moment_kgm[k];
    inertia_c[k] = data.inertia_O_kgm2[k];
    momentum_c[k] = data.IV[k];
    // I crm(V) with I = [I_O, [h]x; [h]x^T, m 1] and crm(V) = [[w]x, 0; [v]x, [w]x].
    const Eigen::Matrix3d hx = skew(data.first_moment_kgm[k]);
    const Eigen::Matrix3d wx = skew(data.V[k].top);
    const Eigen::Matrix3d vx = skew(data.V[k].bottom);
    Matrix6 p;
    p.topLeftCorner<3, 3>().noalias() = data.inertia_O_kgm2[k] * wx + hx * vx;
    p.topRightCorner<3, 3>().noalias() = hx * wx;
    p.bottomLeftCorner<3, 3>().noalias() = -hx * wx;
    p.bottomLeftCorner<3, 3>() += data.mass_kg[k] * vx;
    p.bottomRightCorner<3, 3>() = data.mass_kg[k] * wx;
    b_c[k] = p + p.transpose();
  }
  for (int o = n - 1; o >= 0; --o) {
    const auto k = static_cast<std::size_t>(tree.order[static_cast<std::size_t>(o)]);
    const int parent = tree.parent[k];
    if (parent < 0) continue;
    const auto pk = static_cast<std::size_t>(parent);
    mass_c[pk] += mass_c[k];
    moment_c[pk] += moment_c[k];
    inertia_c[pk] += inertia_c[k];
    momentum_c[pk] += momentum_c[k];
    b_c[pk] += b_c[k];
  }
  const SpatialVector& ground_accel = data.ground_accel;
  const SpatialVector zero{};
  std::array<SpatialVector, kMaxBodies> a_i{};   // I^C_i s_i
  std::array<SpatialVector, kMaxBodies> b_i{};   // -B_i s_i - s_i x* (IV)^C_i
  std::array<SpatialVector, kMaxBodies> d_q{};   // sum over j's subtree of dF/dq_j
  std::array<SpatialVector, kMaxBodies> d_qd{};  // sum over j's subtree of dF/dqd_j
  std::array<SpatialVector, kMaxBodies> w_j{};
  std::array<SpatialVector, kMaxBodies> u_j{};
  for (int j = 0; j < n; ++j) {
    const auto kj = static_cast<std::size_t>(j);
    const int pj = tree.parent[kj];
    const SpatialVector& s = data.s[kj];
    const SpatialVector& V_p = pj < 0 ? zero : data.V[static_cast<std::size_t>(pj)];
    const SpatialVector& A_p = pj < 0 ? ground_accel : data.A[static_cast<std::size_t>(pj)];
    const SpatialVector w = crossMotion(V_p, s);
    const SpatialVector u = scaled(crossMotion(s, A_p) + crossMotion(w, V_p), -1.0);
    w_j[kj] = w;
    u_j[kj] = u;
    const SpatialVector ic_s = applyInertia(mass_c[kj], moment_c[kj], inertia_c[kj], s);
    const SpatialVector ic_u = applyInertia(mass_c[kj], moment_c[kj], inertia_c[kj], u);
    const SpatialVector ic_w = applyInertia(mass_c[kj], moment_c[kj], inertia_c[kj], w);
    const Vector6 bs = b_c[kj] * stacked(s);
    const Vector6 bw = b_c[kj] * stacked(w);
    const SpatialVector s_x_momentum = crossForce(s, momentum_c[kj]);
    a_i[kj] = ic_s;
    b_i[kj] = scaled(split(bs) + s_x_momentum, -1.0);
    d_q[kj] = crossForce(s, data.F_tot[kj]) + ic_u - split(bw) + crossForce(w, momentum_c[kj]);
    d_qd[kj] = scaled(ic_w, 2.0) - split(bs) + s_x_momentum;
  }
  for (int j = 0; j < n; ++j) {
    const auto kj = static_cast<std::size_t>(j);
    for (int i = 0; i < n; ++i) {
      const auto ki = static_cast<std::size_t>(i);
      if (i != j && tree.supports[kj][ki]) {  // i a descendant of j
        dtau_dq(i, j) = dot(u_j[kj], a_i[ki]) + dot(w_j[kj], b_i[ki]);
        dtau_dqd(i, j) = 2.0 * dot(w_j[kj], a_i[ki]) + dot(data.s[kj], b_i[ki]);
      } else if (tree.supports[ki][kj]) {  // i an ancestor of, or equal to, j
        dtau_dq(i, j) = dot(data.s[ki], d_q[kj]);
        dtau_dqd(i, j) = dot(data.s[ki], d_qd[kj]);
      }
    }
  }
}

}  // namespace fullarm::arm
