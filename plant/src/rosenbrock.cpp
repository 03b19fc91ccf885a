#include "fullarm/plant/rosenbrock.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace fullarm::plant {

namespace {

// Rodas3 coefficients in the transformed form (Sandu et al. 1997, Table 4; KPP "RODAS-3"):
// gamma = 1/2, A: a31 = a41 = 2, a43 = 1; C: c21 = 4, c31 = c41 = 1, c32 = c42 = -1, c43 = -8/3;
// m = (2, 0, 1, 1); error weights e = (0, 0, 0, 1); local order 3 (controller exponent 1/3).
constexpr double kGamma = 0.5;
constexpr double kC21 = 4.0;
constexpr double kC31 = 1.0;
constexpr double kC32 = -1.0;
constexpr double kC41 = 1.0;
constexpr double kC42 = -1.0;
constexpr double kC43 = -8.0 / 3.0;
// Rodas4 coefficients (RODAS of Hairer & Wanner, Solving ODEs II, 2nd ed., 1996, sec. IV.7,
// order 4(3); the values of the authors' Fortran code rodas.f, METH = 1), same transformed form: gamma = 1/4; stage i
// is evaluated at y0 + sum_j a_ij k_j; G k_i = f(stage i) + sum_j (c_ij / h) k_j. Stiffly accurate: stage 6 sits at
// stage 5 + k5 (the embedded order-3 solution), y1 = stage 6 + k6, error estimate k6; local order 4 (controller
// exponent 1/4).
constexpr double kGamma4 = 0.25;
constexpr double kA4[4][4] = {{1.544, 0.0, 0.0, 0.0},
                              {0.9466785280815826, 0.2557011698983284, 0.0, 0.0},
                              {3.314825187068521, 2.896124015972201, 0.9986419139977817, 0.0},
                              {1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950}};
constexpr double kC4[5][5] = {
    {-5.6688, 0.0, 0.0, 0.0, 0.0},
    {-2.430093356833875, -0.2063599157091915, 0.0, 0.0, 0.0},
    {-0.1073529058151375, -9.594562251023355, -20.47028614809616, 0.0, 0.0},
    {7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160, 0.0},
    {8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136, -6.058818238834054}};
// Rosenbrock-W methods of Rang & Angermann, "New Rosenbrock W-methods of order 3 for partial
// differential algebraic equations of index 1", BIT Numer. Math. 45 (2005) 761-787, in their original form
// (I - h gamma J) k_i = h f(y0 + sum_j alpha_ij k_j) + h J sum_j gamma_ij k_j, y1 = y0 + sum b_i k_i,
// embedded bhat; converted to the transformed form of attempt() by setMethod() (Hairer & Wanner, Solving ODEs II,
// sec. IV.7, eq. (7.25)). The W order conditions hold for any J: b alpha 1 = 1/2 and b (Gamma - gamma I) 1 = -gamma
// at order 2, as checked by the order tests with a perturbed Jacobian (tests/plant/rosenbrock_test.cpp).
struct WMethodTable {
  int stages;
  double gamma;
  double alpha[4][4];
  double gamma_ij[4][4];  // strictly lower part of Gamma (its diagonal is gamma)
  double b[4];
  double bhat[4];
};
// ROS34PW2: 4 stages, stiffly accurate, L-stable; embedded order 2 with R(inf) = 0.48.
constexpr WMethodTable kRos34pw2 = {
    4,
    4.3586652150845900e-01,
    {{0.0, 0.0, 0.0, 0.0},
     {8.7173304301691801e-01, 0.0, 0.0, 0.0},
     {8.4457060015369423e-01, -1.1299064236484185e-01, 0.0, 0.0},
     {0.0, 0.0, 1.0, 0.0}},
    {{0.0, 0.0, 0.0, 0.0},
     {-8.7173304301691801e-01, 0.0, 0.0, 0.0},
     {-9.0338057013044082e-01, 5.4180672388095326e-02, 0.0, 0.0},
     {2.4212380706095346e-01, -1.2232505839045147e+00, 5.4526025533510214e-01, 0.0}},
    {2.4212380706095346e-01, -1.2232505839045147e+00, 1.5452602553351020e+00, 4.3586652150845900e-01},
    {3.7810903145819369e-01, -9.6042292212423178e-02, 5.0000000000000000e-01, 2.1793326075422950e-01}};
constexpr double kSafety = 0.9;
constexpr double kMinFactor = 0.2;
constexpr double kMaxFactor = 5.0;
constexpr double kSmallestStep_s = 1e-14;

}  // namespace

void RosenbrockIntegrator::setMethod(RosenbrockMethod method) noexcept {
  method_ = method;
  factor_valid_ = false;
  if (!isWMethod(method)) return;
  // Equation R12 (reports/equations.md): with Gamma = (gamma_ij) lower triangular (diagonal gamma) and
  // u_i = sum_j Gamma_ij k_j, the stages become G u_i = f(y0 + sum_j a_ij u_j) + sum_j (c_ij / h) u_j with
  // G = I / (h gamma) - J, a = alpha Gamma^-1, c = diag(1 / gamma) - Gamma^-1, m = b Gamma^-1, e = (b - bhat) Gamma^-1.
  const WMethodTable& t = kRos34pw2;
  const int s = t.stages;
  double inv[4][4] = {};  // Gamma^-1 by forward substitution
  for (int j = 0; j < s; ++j) {
    inv[j][j] = 1.0 / t.gamma;
    for (int i = j + 1; i < s; ++i) {
      double sum = 0.0;
      for (int k = j; k < i; ++k) sum += t.gamma_ij[i][k] * inv[k][j];
      inv[i][j] = -sum / t.gamma;
    }
  }
  WTableau w{};
  w.stages = s;
  w.gamma = t.gamma;
  for (int i = 0; i < s; ++i) {
    for (int j = 0; j < i; ++j) {
      for (int k = j; k < i; ++k) w.a[i][j] += t.alpha[i][k] * inv[k][j];
      w.c[i][j] = -inv[i][j];
    }
  }
  for (int j = 0; j < s; ++j) {
    for (int i = j; i < s; ++i) {
      w.m[j] += t.b[i] * inv[i][j];
      w.e[j] += (t.b[i] - t.bhat[i]) * inv[i][j];
    }
  }
  w_tab_ = w;
}

void RosenbrockIntegrator::configure(int n, const double* atol, double rtol, long max_steps_per_call,
                                     const RosenbrockSystem& system) {
  if (n < 1 || n > kMaxRosenbrockStates) throw std::invalid_argument("Rosenbrock integrator: state size out of range");
  if (!(rtol > 0.0) || max_steps_per_call < 1)
    throw std::invalid_argument("Rosenbrock integrator: bad tolerance or step budget");
  if (system.rhs == nullptr || system.jacobian == nullptr)
    throw std::invalid_argument("Rosenbrock integrator: missing f or J");
  n_ = n;
  rtol_ = rtol;
  max_steps_ = max_steps_per_call;
  sys_ = system;
  atol_.resize(n);
  for (int i = 0; i < n; ++i) {
    if (!(atol[i] > 0.0)) throw std::invalid_argument("Rosenbrock integrator: absolute tolerances must be positive");
    atol_[i] = atol[i];
  }
  for (Vector* v : {&y0_, &f0_, &y1_, &k1_, &k2_, &k3_, &k4_, &stage_, &fstage_, &stage_scratch_}) v->setZero(n);
  for (Vector& v : ks_) v.setZero(n);
  blocks_ = 0;
  border_ = n;
  jac_.setZero(n, n);
  g_.setZero(n, n);
  stats_ = {};
  factor_valid_ = false;
  structure_valid_ = false;
}

void RosenbrockIntegrator::setBlockStructure(int blocks) {
  if (blocks < 0 || blocks * kRosenbrockBlock > n_)
    throw std::invalid_argument("Rosenbrock integrator: block structure too large");
  blocks_ = blocks;
  border_ = n_ - blocks * kRosenbrockBlock;
  factor_valid_ = false;
  structure_valid_ = false;
  if (blocks_ > 0) {
    w_.setZero(blocks_ * kRosenbrockBlock, border_);
    schur_.setZero(border_, border_);
    schur_reduced_.setZero(border_ / 2, border_ / 2);
    z_.setZero(n_);
  }
}

namespace {

// In-place LU with partial pivoting of the n x n column-major matrix a (leading dimension ld):
// P a = L U, row k swapped with piv[k] at elimination step k; the diagonal holds 1 / U_kk, so
// the back substitution multiplies (a division's latency dominated the 6 x 6 solve). Plain loops: at the sizes here
// (4 to 20) they beat a general library LU's dispatch overhead several times. False if a pivot
// is zero or not finite.
bool luFactor(double* a, int ld, int n, int* piv) noexcept {
  auto at = [a, ld](int i, int j) -> double& { return a[i + static_cast<std::ptrdiff_t>(j) * ld]; };
  for (int k = 0; k < n; ++k) {
    int p = k;
    double best = std::abs(at(k, k));
    for (int i = k + 1; i < n; ++i) {
      if (std::abs(at(i, k)) > best) {
        best = std::abs(at(i, k));
        p = i;
      }
    }
    piv[k] = p;
    if (!(best > 0.0) || !std::isfinite(best)) return false;
    if (p != k) {
      for (int j = 0; j < n; ++j) std::swap(at(k, j), at(p, j));
    }
    const double inv = 1.0 / at(k, k);
    at(k, k) = inv;  // stored as 1 / U_kk: the solves multiply
    for (int i = k + 1; i < n; ++i) at(i, k) *= inv;
    for (int j = k + 1; j < n; ++j) {
      const double akj = at(k, j);
      if (akj == 0.0) continue;
      double* colj = &at(0, j);
      const double* colk = &at(0, k);
      for (int i = k + 1; i < n; ++i) colj[i] -= colk[i] * akj;
    }
  }
  return true;
}

// x = (P^T L U)^-1 x in place with the factors of luFactor.
void luSolve(const double* __restrict a, int ld, int n, const int* __restrict piv, double* __restrict x) noexcept {
  // (__restrict: the factors and x never overlap, so the compiler needs no aliasing checks in the
  // short inner loops.)
  auto at = [a, ld](int i, int j) { return a[i + static_cast<std::ptrdiff_t>(j) * ld]; };
  for (int k = 0; k < n; ++k) {
    if (piv[k] != k) std::swap(x[k], x[piv[k]]);
  }
  for (int k = 0; k < n; ++k) {
    const double xk = x[k];
    if (xk == 0.0) continue;
    for (int i = k + 1; i < n; ++i) x[i] -= at(i, k) * xk;
  }
  for (int k = n - 1; k >= 0; --k) {
    x[k] *= at(k, k);
    const double xk = x[k];
    for (int i = 0; i < k; ++i) x[i] -= at(i, k) * xk;
  }
}

// luFactor and luSolve with the size known at compile time (the single joint's 6 states, the
// 4-state hydraulic blocks, the arm's 7 x 7 halved Schur system): unrolled by the compiler, several times faster than
// the runtime-size loops at these sizes. The fixed-size factorisation returns the row permutation itself (row i of P a
// is row perm[i] of a) instead of the swap sequence, so the solve gathers x once into a local array that lives in
// registers: updating x in place in memory, the partially vectorised substitutions stalled on store-to-load forwarding.
template <int N>
void luSolveFixed(const double* __restrict a, const int* __restrict perm, double* __restrict x) noexcept {
  // (Complete unrolling, so that v is a set of registers; GCC leaves the nested loops rolled.)
  double v[N];
#pragma GCC unroll 16
  for (int i = 0; i < N; ++i) v[i] = x[perm[i]];
#pragma GCC unroll 16
  for (int k = 0; k < N; ++k) {
#pragma GCC unroll 16
    for (int i = k + 1; i < N; ++i) v[i] -= a[i + k * N] * v[k];
  }
#pragma GCC unroll 16
  for (int k = N - 1; k >= 0; --k) {
    v[k] *= a[k + k * N];
#pragma GCC unroll 16
    for (int i = 0; i < k; ++i) v[i] -= a[i + k * N] * v[k];
  }
#pragma GCC unroll 16
  for (int i = 0; i < N; ++i) x[i] = v[i];
}
template <int N>
bool luFactorFixed(double* a, int* piv) noexcept {
#pragma GCC unroll 16
  for (int k = 0; k < N; ++k) {
    int p = k;
    double best = std::abs(a[k + k * N]);
#pragma GCC unroll 16
    for (int i = k + 1; i < N; ++i) {
      if (std::abs(a[i + k * N]) > best) {
        best = std::abs(a[i + k * N]);
        p = i;
      }
    }
    piv[k] = p;
    if (!(best > 0.0) || !std::isfinite(best)) return false;
    if (p != k) {
#pragma GCC unroll 16
      for (int j = 0; j < N; ++j) std::swap(a[k + j * N], a[p + j * N]);
    }
    const double inv = 1.0 / a[k + k * N];
    a[k + k * N] = inv;  // stored as 1 / U_kk: the solves multiply
#pragma GCC unroll 16
    for (int i = k + 1; i < N; ++i) a[i + k * N] *= inv;
#pragma GCC unroll 16
    for (int j = k + 1; j < N; ++j) {
      const double akj = a[k + j * N];
#pragma GCC unroll 16
      for (int i = k + 1; i < N; ++i) a[i + j * N] -= a[i + k * N] * akj;
    }
  }
  // Swap sequence -> permutation (the same swaps applied to the identity).
  int perm[N];
  for (int i = 0; i < N; ++i) perm[i] = i;
  for (int k = 0; k < N; ++k) std::swap(perm[k], perm[piv[k]]);
  for (int i = 0; i < N; ++i) piv[i] = perm[i];
  return true;
}

// Inverse of a 4 x 4 diagonal block D of the Newton matrix; false if singular or not finite. When
// D = [A 0; C E] in 2 x 2 blocks (the plant's spool states do not depend on its pressures), by the
// 2 x 2 cofactor inverses, D^-1 = [A^-1 0; -E^-1 C A^-1 E^-1]; otherwise by Eigen's 4 x 4
// cofactor inverse. Both are invariant under the rows' very different scales.
// R10: block elimination with a Schur complement on the border (reports/equations.md).
bool invertBlock(const Eigen::Matrix4d& dk, Eigen::Matrix4d& inv) noexcept {
  if (dk(0, 2) == 0.0 && dk(0, 3) == 0.0 && dk(1, 2) == 0.0 && dk(1, 3) == 0.0) {
    const double det_a = dk(0, 0) * dk(1, 1) - dk(0, 1) * dk(1, 0);
    const double det_e = dk(2, 2) * dk(3, 3) - dk(2, 3) * dk(3, 2);
    if (!(det_a != 0.0 && det_e != 0.0)) return false;
    const double ia = 1.0 / det_a;
    const double ie = 1.0 / det_e;
    // A^-1 and E^-1 by cofactors (plain scalars: Eigen's small fixed products cost more here).
    const double a00 = dk(1, 1) * ia, a01 = -dk(0, 1) * ia, a10 = -dk(1, 0) * ia, a11 = dk(0, 0) * ia;
    const double e00 = dk(3, 3) * ie, e01 = -dk(2, 3) * ie, e10 = -dk(3, 2) * ie, e11 = dk(2, 2) * ie;
    // T = C A^-1, lower-left block = -(E^-1 T).
    const double t00 = dk(2, 0) * a00 + dk(2, 1) * a10, t01 = dk(2, 0) * a01 + dk(2, 1) * a11;
    const double t10 = dk(3, 0) * a00 + dk(3, 1) * a10, t11 = dk(3, 0) * a01 + dk(3, 1) * a11;
    inv << a00, a01, 0.0, 0.0,                                         //
        a10, a11, 0.0, 0.0,                                            //
        -(e00 * t00 + e01 * t10), -(e00 * t01 + e01 * t11), e00, e01,  //
        -(e10 * t00 + e11 * t10), -(e10 * t01 + e11 * t11), e10, e11;
    return inv.allFinite();
  }
  double det = 0.0;
  bool invertible = false;
  dk.computeInverseAndDetWithCheck(inv, det, invertible, 0.0);
  return invertible && std::isfinite(det) && inv.allFinite();
}

// Dispatch on the sizes that occur (4: hydraulic block, 6: one joint, 7: the arm's halved Schur
// system); `piv` is the swap
// sequence of luFactor or the permutation of luFactorFixed, consistently per size.
bool luFactorAny(double* a, int ld, int n, int* piv) noexcept {
  if (n == ld && n == 4) return luFactorFixed<4>(a, piv);
  if (n == ld && n == 6) return luFactorFixed<6>(a, piv);
  if (n == ld && n == 7) return luFactorFixed<7>(a, piv);
  return luFactor(a, ld, n, piv);
}
void luSolveAny(const double* a, int ld, int n, const int* piv, double* x) noexcept {
  if (n == ld && n == 4) {
    luSolveFixed<4>(a, piv, x);
  } else if (n == ld && n == 6) {
    luSolveFixed<6>(a, piv, x);
  } else if (n == ld && n == 7) {
    luSolveFixed<7>(a, piv, x);
  } else {
    luSolve(a, ld, n, piv, x);
  }
}

}  // namespace

bool RosenbrockIntegrator::factor(double h) noexcept {
  // A W-method reuses the factorisation while J and h stay (every step of a period with an unchanged step).
  if (factor_valid_ && h == factored_h_) return true;
  factor_valid_ = false;
  const double gamma = isWMethod(method_) ? w_tab_.gamma : (method_ == RosenbrockMethod::kRodas4 ? kGamma4 : kGamma);
  const double d = 1.0 / (h * gamma);
  ++stats_.factorizations;
  factored_h_ = h;
  factor_valid_ = factorG(d);
  return factor_valid_;
}

bool RosenbrockIntegrator::factorG(double d) noexcept {
  if (blocks_ == 0) {
    g_ = -jac_;
    g_.diagonal().array() += d;
    return luFactorAny(g_.data(), static_cast<int>(g_.rows()), n_, pivots_.data());
  }
  // (At compile-time size for the whole arm's border of seven angles and seven velocities.)
  return border_ == 2 * kFixedHalfBorder ? factorBlocks<2 * kFixedHalfBorder>(d) : factorBlocks<0>(d);
}

template <int M>
// R10: block elimination with a Schur complement on the border (reports/equations.md).
bool RosenbrockIntegrator::factorBlocks(double d) noexcept {
  // G = [D B; C E] with D block diagonal: invert each D_k, W = D^-1 B, S = E - C W. B_k (the
  // border columns of block k's rows) and C (the block columns of the border rows) are mostly
  // exact zeros; only nonzero columns of B_k are solved for and used. The 4 x 4 blocks are
  // inverted explicitly (cofactors: invariant under the rows' very different scales), so every
  // later solve with them is a matrix-vector product.
  const int nb = blocks_ * kRosenbrockBlock;
  const int m = M > 0 ? M : border_;
  const int ld = static_cast<int>(jac_.rows());
  const double* jac = jac_.data();
  double* schur = schur_.data();  // m x m, column-major
  for (int j = 0; j < m; ++j) {
    const double* col = jac + static_cast<std::ptrdiff_t>(nb + j) * ld + nb;
    for (int i = 0; i < m; ++i) schur[i + j * m] = -col[i];
    schur[j + j * m] += d;
  }
  // Second-order border [x; v] with x' = v exactly (J's x rows hold only the 1 at v): the x rows
  // of S are (d I, -I) and C has no x rows, so x = (b_x + v) / d and the v rows reduce to the
  // half-size system (S_vv + S_vx / d) v = b_v - S_vx b_x / d.
  // The structure found below (this flag, and the nonzero columns of B_k and C_k) depends on J
  // only: it is found once per Jacobian, not again when a rejected step refactorises with the same J.
  const bool find_structure = !structure_valid_;
  const int p = m / 2;
  if (find_structure)
    second_order_border_ = m % 2 == 0 && p > 0 && [&]() noexcept {
      // Sum of |J_x - [0 I 0]| over the x rows: zero exactly when the pattern holds (a sum of
      // non-negative terms; NaN fails the test). Branch-free, so it vectorises: an entry-by-entry
      // comparison cost a third of the factorisation.
      double deviation = 0.0;
      for (int c = 0; c < n_; ++c) {
        const double* col = jac + static_cast<std::ptrdiff_t>(c) * ld + nb;
        const int one = c - nb - p;  // row of the expected 1 in this column, if in [0, p)
        if (one < 0 || one >= p) {
          for (int i = 0; i < p; ++i) deviation += std::abs(col[i]);
        } else {
          for (int i = 0; i < one; ++i) deviation += std::abs(col[i]);
          deviation += std::abs(col[one] - 1.0);
          for (int i = one + 1; i < p; ++i) deviation += std::abs(col[i]);
        }
      }
      return deviation == 0.0;
    }();
  for (int k = 0; k < blocks_; ++k) {
    const int r = k * kRosenbrockBlock;
    Eigen::Matrix4d dk = -jac_.block<4, 4>(r, r);
    dk.diagonal().array() += d;
    Eigen::Matrix4d& inv = block_inv_[static_cast<std::size_t>(k)];
    if (!invertBlock(dk, inv)) return false;
    // Columns of C_k (block k's columns of the border rows) that hold a nonzero: the others add
    // exact zeros to S here and to the border in every solve (on the plant, the spool columns).
    int& c_count = c_count_[static_cast<std::size_t>(k)];
    if (find_structure) {
      c_count = 0;
      for (int c = 0; c < kRosenbrockBlock; ++c) {
        const double* col = jac + static_cast<std::ptrdiff_t>(r + c) * ld + nb;
        double sum = 0.0;  // a sum of |entries| (branch-free, so it vectorises; NaN counts as nonzero)
        if (second_order_border_) {
          for (int i = p; i < m; ++i) sum += std::abs(col[i]);
        } else {
          for (int i = 0; i < m; ++i) sum += std::abs(col[i]);
        }
        if (!(sum == 0.0)) c_cols_[static_cast<std::size_t>(k * kRosenbrockBlock + c_count++)] = c;
      }
    }
    int& count = nonzero_count_[static_cast<std::size_t>(k)];
    if (find_structure) {
      count = 0;
      for (int j = 0; j < m; ++j) {
        const double* col = jac + static_cast<std::ptrdiff_t>(nb + j) * ld + r;
        const double sum = (std::abs(col[0]) + std::abs(col[1])) + (std::abs(col[2]) + std::abs(col[3]));
        if (!(sum == 0.0)) nonzero_cols_[static_cast<std::size_t>(k * kMaxRosenbrockStates + count++)] = j;
      }
    }
    for (int q = 0; q < count; ++q) {
      const int j = nonzero_cols_[static_cast<std::size_t>(k * kMaxRosenbrockStates + q)];
      const Eigen::Vector4d bj = -jac_.block<4, 1>(r, nb + j);
      const Eigen::Vector4d wj = inv * bj;
      w_.block<4, 1>(r, j) = wj;
      // S -= C_k w_j with C = -J_mh: S(:, j) += J(border, block k) w_j.
      for (int qc = 0; qc < c_count; ++qc) {
        const int c = c_cols_[static_cast<std::size_t>(k * kRosenbrockBlock + qc)];
        const double* col = jac + static_cast<std::ptrdiff_t>(r + c) * ld + nb;
        double* s_j = schur + static_cast<std::ptrdiff_t>(j) * m;
        const double wjc = wj[c];
        if (second_order_border_) {
          for (int i = p; i < m; ++i) s_j[i] += col[i] * wjc;
        } else {
          for (int i = 0; i < m; ++i) s_j[i] += col[i] * wjc;
        }
      }
    }
  }
  structure_valid_ = true;
  if (second_order_border_) {
    inv_d_ = 1.0 / d;
    double* reduced = schur_reduced_.data();  // p x p
    for (int j = 0; j < p; ++j) {
      for (int i = 0; i < p; ++i) reduced[i + j * p] = schur[p + i + (p + j) * m] + schur[p + i + j * m] * inv_d_;
    }
    return luFactorAny(reduced, p, p, pivots_.data());
  }
  return luFactorAny(schur, m, m, pivots_.data());
}

void RosenbrockIntegrator::solve(const Vector& b, Vector& x) noexcept {
  if (blocks_ == 0) {
    x = b;
    luSolveAny(g_.data(), static_cast<int>(g_.rows()), n_, pivots_.data(), x.data());
    return;
  }
  const int nb = blocks_ * kRosenbrockBlock;
  const int m = border_;
  for (int k = 0; k < blocks_; ++k) {
    const int r = k * kRosenbrockBlock;
    z_.segment<4>(r).noalias() = block_inv_[static_cast<std::size_t>(k)] * b.segment<4>(r);
  }
  // Border: S x_m = b_m - C z = b_m + J_mh z (plain loops: the blocks are tiny and sparse).
  double* xm = x.data() + nb;
  for (int i = 0; i < m; ++i) xm[i] = b[nb + i];
  if (second_order_border_ && m == 2 * kFixedHalfBorder) {
    solveHalvedBorder<kFixedHalfBorder>(xm);
  } else if (second_order_border_) {
    solveHalvedBorder<0>(xm);
  } else {
    solveBorder(xm);
  }
  // x_h = z - W x_m over the nonzero columns of each block.
  for (int k = 0; k < blocks_; ++k) {
    const int r = k * kRosenbrockBlock;
    Eigen::Vector4d xk = z_.segment<4>(r);
    for (int q = 0; q < nonzero_count_[static_cast<std::size_t>(k)]; ++q) {
      const int j = nonzero_cols_[static_cast<std::size_t>(k * kMaxRosenbrockStates + q)];
      xk -= w_.block<4, 1>(r, j) * xm[j];
    }
    x.segment<4>(r) = xk;
  }
}

template <int P>
// R10: block elimination with a Schur complement on the border (reports/equations.md).
void RosenbrockIntegrator::solveHalvedBorder(double* xm) const noexcept {
  // Second-order border [x; v] (see factorG): C reaches the v rows only; the v rows are then the
  // half-size system. In a local array of the p velocities, which the compiler keeps in registers
  // when P is known (the plant's seven joints); the same operations in the same order as at run-time p.
  const int p = P > 0 ? P : border_ / 2;
  const int nb = blocks_ * kRosenbrockBlock;
  const int ld = static_cast<int>(jac_.rows());
  const double* jac = jac_.data();
  double xv[kMaxRosenbrockStates / 2];
  for (int i = 0; i < p; ++i) xv[i] = xm[p + i];
  for (int k = 0; k < blocks_; ++k) {
    for (int q = 0; q < c_count_[static_cast<std::size_t>(k)]; ++q) {
      const int c = k * kRosenbrockBlock + c_cols_[static_cast<std::size_t>(k * kRosenbrockBlock + q)];
      const double zc = z_[c];
      const double* col = jac + static_cast<std::ptrdiff_t>(c) * ld + nb + p;
      for (int i = 0; i < p; ++i) xv[i] += col[i] * zc;
    }
  }
  const double* s_vx = schur_.data() + p;  // S(p + i, j) = s_vx[i + j * ld_s]
  const auto ld_s = static_cast<std::ptrdiff_t>(schur_.rows());
  for (int j = 0; j < p; ++j) {
    const double bx = xm[j] * inv_d_;
    for (int i = 0; i < p; ++i) xv[i] -= s_vx[i + j * ld_s] * bx;
  }
  luSolveAny(schur_reduced_.data(), static_cast<int>(schur_reduced_.rows()), p, pivots_.data(), xv);
  for (int i = 0; i < p; ++i) {
    xm[i] = (xm[i] + xv[i]) * inv_d_;
    xm[p + i] = xv[i];
  }
}

void RosenbrockIntegrator::solveBorder(double* xm) const noexcept {
  const int nb = blocks_ * kRosenbrockBlock;
  const int m = border_;
  const int ld = static_cast<int>(jac_.rows());
  const double* jac = jac_.data();
  for (int k = 0; k < blocks_; ++k) {
    for (int q = 0; q < c_count_[static_cast<std::size_t>(k)]; ++q) {
      const int c = k * kRosenbrockBlock + c_cols_[static_cast<std::size_t>(k * kRosenbrockBlock + q)];
      const double zc = z_[c];
      if (zc == 0.0) continue;
      const double* col = jac + static_cast<std::ptrdiff_t>(c) * ld + nb;
      for (int i = 0; i < m; ++i) xm[i] += col[i] * zc;
    }
  }
  luSolveAny(schur_.data(), static_cast<int>(schur_.rows()), m, pivots_.data(), xm);
}

double RosenbrockIntegrator::attempt(double h) noexcept {
  if (!factor(h)) return std::numeric_limits<double>::infinity();
  if (method_ == RosenbrockMethod::kRodas4) return attemptRodas4(h);
  if (isWMethod(method_)) return attemptW(h);
  auto solve = [this](const Vector& b, Vector& x) { this->solve(b, x); };
  const double inv_h = 1.0 / h;
  solve(f0_, k1_);
  fstage_ = f0_ + (kC21 * inv_h) * k1_;  // stage 2 sits at y0 (a21 = 0): f(y0) reused
  solve(fstage_, k2_);
  stage_ = y0_ + 2.0 * k1_;
  sys_.rhs(sys_.user, stage_.data(), fstage_.data());
  ++stats_.rhs_evals;
  fstage_ += inv_h * (kC31 * k1_ + kC32 * k2_);
  solve(fstage_, k3_);
  stage_ += k3_;
  sys_.rhs(sys_.user, stage_.data(), fstage_.data());
  ++stats_.rhs_evals;
  fstage_ += inv_h * (kC41 * k1_ + kC42 * k2_ + kC43 * k3_);
  solve(fstage_, k4_);
  y1_ = stage_ + k4_;  // stiffly accurate: y1 = stage 4 + k4
  return errorNorm(k4_);
}

double RosenbrockIntegrator::attemptRodas4(double h) noexcept {
  // R11 (reports/equations.md). Stages 1..6 (k_1..k_6 in ks_[0..5]); stage 1 sits at y0 (f0
  // from the Jacobian pass).
  const double inv_h = 1.0 / h;
  solve(f0_, ks_[0]);
  for (int i = 1; i < 6; ++i) {
    if (i < 5) {
      stage_ = y0_;
      for (int j = 0; j < i; ++j) stage_ += kA4[i - 1][j] * ks_[static_cast<std::size_t>(j)];
    } else {
      stage_ += ks_[4];  // stage 6 = stage 5 + k5 (the embedded solution)
    }
    sys_.rhs(sys_.user, stage_.data(), fstage_.data());
    ++stats_.rhs_evals;
    for (int j = 0; j < i; ++j) fstage_ += (kC4[i - 1][j] * inv_h) * ks_[static_cast<std::size_t>(j)];
    solve(fstage_, ks_[static_cast<std::size_t>(i)]);
  }
  const Vector& k6 = ks_[5];
  y1_ = stage_ + k6;  // stiffly accurate: y1 = stage 6 + k6
  return errorNorm(k6);
}

double RosenbrockIntegrator::attemptW(double h) noexcept {
  // R12 (reports/equations.md): stage 1 sits at y0 (f0 from the Jacobian pass or advance()).
  const WTableau& w = w_tab_;
  const double inv_h = 1.0 / h;
  solve(f0_, ks_[0]);
  for (int i = 1; i < w.stages; ++i) {
    stage_ = y0_;
    for (int j = 0; j < i; ++j) stage_ += w.a[i][j] * ks_[static_cast<std::size_t>(j)];
    sys_.rhs(sys_.user, stage_.data(), fstage_.data());
    ++stats_.rhs_evals;
    for (int j = 0; j < i; ++j) fstage_ += (w.c[i][j] * inv_h) * ks_[static_cast<std::size_t>(j)];
    solve(fstage_, ks_[static_cast<std::size_t>(i)]);
  }
  y1_ = y0_;
  stage_scratch_.setZero();
  for (int j = 0; j < w.stages; ++j) {
    y1_ += w.m[j] * ks_[static_cast<std::size_t>(j)];
    stage_scratch_ += w.e[j] * ks_[static_cast<std::size_t>(j)];
  }
  return errorNorm(stage_scratch_);
}

double RosenbrockIntegrator::errorNorm(const Vector& estimate) const noexcept {
  // Weighted RMS of the embedded error estimate, weights atol + rtol max(|y0|, |y1|).
  double sum = 0.0;
  for (int i = 0; i < n_; ++i) {
    const double w = atol_[i] + rtol_ * std::max(std::abs(y0_[i]), std::abs(y1_[i]));
    const double e = estimate[i] / w;
    sum += e * e;
  }
  const double err = std::sqrt(sum / n_);
  return std::isfinite(err) ? err : std::numeric_limits<double>::infinity();
}

namespace {

constexpr core::RtStatus kNonFiniteRhs =
    core::RtStatus::fault(core::RtCode::kBadState, core::kFaultNonFiniteState, "non-finite right-hand side");
constexpr core::RtStatus kTooManySteps =
    core::RtStatus::fault(core::RtCode::kSolverFailure, core::kFaultTooManySteps, "too many steps in one period");
constexpr core::RtStatus kStepTooSmall =
    core::RtStatus::fault(core::RtCode::kSolverFailure, core::kFaultStepTooSmall, "step size underflow");

}  // namespace

core::RtStatus RosenbrockIntegrator::advance(double* y, double duration_s) noexcept {
  Eigen::Map<Vector> state(y, n_);
  y0_ = state;
  double t = 0.0;
  const bool w_method = isWMethod(method_);
  bool need_jacobian = true;  // W-methods: once per call (a control period), see below
  bool need_f0 = false;       // W-methods: f(y0) without a Jacobian after an accepted step
  bool rejected_here = false;
  int rejections_in_a_row = 0;
  long attempts = 0;
  while (t < duration_s) {
    const double remaining = duration_s - t;
    // Equal subdivisions of what is left, so the last step ends on the boundary exactly.
    const double pieces = std::ceil(remaining / h_ * (1.0 - 1e-9));
    const bool last = pieces <= 1.0;
    const double h = last ? remaining : remaining / pieces;
    if (need_jacobian) {
      sys_.jacobian(sys_.user, y0_.data(), f0_.data(), jac_.data());
      structure_valid_ = false;
      ++stats_.jac_evals;
      ++stats_.rhs_evals;
      need_jacobian = false;
      need_f0 = false;
      factor_valid_ = false;
      if (!f0_.allFinite()) return kNonFiniteRhs;
    } else if (need_f0) {
      sys_.rhs(sys_.user, y0_.data(), f0_.data());
      ++stats_.rhs_evals;
      need_f0 = false;
      if (!f0_.allFinite()) return kNonFiniteRhs;
    }
    if (++attempts > max_steps_) return kTooManySteps;
    const double err = attempt(h);
    // Elementary controller h_new = h (0.9 / err)^(1/3), within [0.2, 5] (no growth right
    // after a rejection).
    const double factor = err > 0.0 ? kSafety * (method_ == RosenbrockMethod::kRodas4 ? std::sqrt(std::sqrt(1.0 / err))
                                                                                      : std::cbrt(1.0 / err))
                                    : kMaxFactor;
    if (err <= 1.0) {
      y0_ = y1_;
      t = last ? duration_s : t + h;
      ++stats_.steps;
      // Rosenbrock: a new Jacobian at every step. W-method: keep J (and its factorisation while h stays).
      (w_method ? need_f0 : need_jacobian) = true;
      h_ = h * std::clamp(factor, kMinFactor, rejected_here ? 1.0 : kMaxFactor);
      rejected_here = false;
      rejections_in_a_row = 0;
    } else {
      ++stats_.rejected;
      rejected_here = true;
      // W-method: a second rejection in a row may be the stale Jacobian's doing; refresh it.
      if (w_method && ++rejections_in_a_row >= 2) {
        need_jacobian = true;
        rejections_in_a_row = 0;
      }
      h_ = h * (std::isfinite(err) ? std::clamp(factor, kMinFactor, 1.0) : 0.25);
      if (h_ < kSmallestStep_s) return kStepTooSmall;
    }
  }
  state = y0_;
  return {};
}

}  // namespace fullarm::plant
