#pragma once
/// @file
/// RosenbrockIntegrator: Rodas3 by default, an adaptive, L-stable, stiffly accurate Rosenbrock method of order 3 with
/// an embedded order-2 error estimate (Sandu et al., "Benchmarking stiff ODE solvers for atmospheric chemistry problems
/// II: Rosenbrock solvers", Atmos. Environ. 31, 1997; Hairer & Wanner, Solving ODEs II, sec. IV.7), for autonomous
/// systems y' = f(y) of up to kMaxRosenbrockStates states, in fixed-capacity storage (no heap after configure()).
///
/// Why a one-step method next to CVODES: the plant's input is a zero-order hold that jumps at
/// every control period. A multistep method (BDF) must restart at order 1 with tiny steps
/// after each jump; a one-step method starts every step from scratch anyway, so it carries its
/// step size across the jump at no cost. Each step needs one Jacobian, one LU factorisation,
/// three right-hand sides and four solves, and no Newton iteration.
///
/// Stages (transformed form, gamma = 1/2, G = I/(h gamma) - J(y0)):
///   G k1 = f(y0)
///   G k2 = f(y0) + 4 k1 / h
///   G k3 = f(y0 + 2 k1) + (k1 - k2) / h
///   G k4 = f(y0 + 2 k1 + k3) + (k1 - k2 - 8/3 k3) / h
///   y1 = y0 + 2 k1 + k3 + k4,   local error estimate k4.
///
/// setMethod(RosenbrockMethod::kRodas4) switches the same integrator (storage, Newton matrix,
/// block elimination, error norm) to RODAS of Hairer & Wanner (Solving ODEs II, sec. IV.7), order
/// 4 with an embedded order-3 estimate, gamma = 1/4: six stages, five new f evaluations and six
/// solves per attempt (equation R11 of reports/equations.md).
///
/// setMethod(RosenbrockMethod::kRos34pw2) selects the Rosenbrock-W method ROS34PW2 of Rang &
/// Angermann ("New Rosenbrock W-methods of order 3 for partial differential algebraic equations of
/// index 1", BIT Numer. Math. 45, 2005, 761-787): order 3 with an embedded order-2 estimate for ANY
/// matrix in place of the Jacobian (the W order conditions), so advance() builds the Jacobian once
/// per call (one control period) and again only after two rejections in a row, evaluates f(y0) by
/// itself at the later steps, and refactorises G only when h changes (equation R12).

#include <Eigen/Core>

#include "fullarm/core/rt_status.hpp"
#include <array>

namespace fullarm::plant {

/// Largest state size RosenbrockIntegrator handles.
inline constexpr int kMaxRosenbrockStates = 60;

/// Size of the independent diagonal blocks of setBlockStructure().
inline constexpr int kRosenbrockBlock = 4;

/// Counters of a RosenbrockIntegrator (since configure() or resetCounters()).
struct RosenbrockStats {
  long steps = 0;      ///< accepted steps
  long rejected = 0;   ///< steps rejected by the error test
  long rhs_evals = 0;  ///< f evaluations (including the one inside each Jacobian call)
  long jac_evals = 0;  ///< Jacobian evaluations (Rodas: one per accepted step; W: one per advance() call + refreshes)
  long factorizations = 0;  ///< LU factorisations of G
};

/// Which Rosenbrock scheme advance() uses.
enum class RosenbrockMethod {
  kRodas3,  ///< order 3(2), 4 stages: 3 f evaluations (one inside the Jacobian pass), 4 solves per attempt
  kRodas4,  ///< order 4(3), 6 stages (Hairer & Wanner's RODAS): 6 f evaluations, 6 solves per attempt
  /// Rosenbrock-W, order 3(2) with any Jacobian approximation, 4 stages, L-stable, stiffly accurate
  /// (ROS34PW2, Rang & Angermann 2005): 4 f evaluations and 4 solves per attempt, Jacobian once per advance().
  kRos34pw2,
};

/// True for the W-methods (kRos34pw2), which keep their order with a stale Jacobian. (The three-stage
/// ROS3PW of the same paper is order 3 only with the exact Jacobian: order 2 with a wrong one, measured.)
[[nodiscard]] constexpr bool isWMethod(RosenbrockMethod method) noexcept {
  return method == RosenbrockMethod::kRos34pw2;
}


/// The right-hand side and its Jacobian, supplied by the caller.
struct RosenbrockSystem {
  /// f(y) into ydot (size n). @rt
  void (*rhs)(void* user, const double* y, double* ydot) noexcept = nullptr;
  /// J = df/dy at y into jac (n x n, column-major) and f(y) into ydot. @rt
  void (*jacobian)(void* user, const double* y, double* ydot, double* jac) noexcept = nullptr;
  void* user = nullptr;
};

/// Adaptive Rodas3, Rodas4 or ROS34PW2 (setMethod) with weighted-RMS error control (the norm CVODES uses):
/// ||e|| = sqrt(mean_i (e_i / (rtol max(|y0_i|, |y1_i|) + atol_i))^2) <= 1.
class RosenbrockIntegrator {
 public:
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxRosenbrockStates, 1>;
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxRosenbrockStates, kMaxRosenbrockStates>;

  /// @param n state size (1..kMaxRosenbrockStates); @param atol absolute tolerances (size n)
  /// @param max_steps_per_call attempted-step budget of one advance()
  /// @throws std::invalid_argument for a bad size, tolerance or system.
  void configure(int n, const double* atol, double rtol, long max_steps_per_call, const RosenbrockSystem& system);

  /// Integrates y (size n, in place) over `duration_s` > 0, carrying the step size proposed by
  /// the previous call; the steps of one call are equal-length subdivisions so the last step
  /// lands on the end exactly. Returns ok, or kSolverFailure with kFaultTooManySteps (the
  /// attempted-step budget is spent) or kFaultStepTooSmall (the step fell below its minimum), or
  /// kBadState with kFaultNonFiniteState (a non-finite right-hand side).
  /// Allocation-free, unbounded time (core/rt_status.hpp): the step count adapts to the solution,
  /// up to max_steps_per_call attempts.
  core::RtStatus advance(double* y, double duration_s) noexcept;

  /// Declares that the first `blocks` * kRosenbrockBlock states form independent blocks of
  /// kRosenbrockBlock states (J has no entries between two different leading blocks), coupled
  /// only through the remaining "border" states. The Newton matrix is then factorised by block
  /// elimination (a Schur complement on the border) instead of a dense LU: the plant's
  /// hydraulic states of one joint couple to the other joints only through q and qd. When the
  /// border is [x; v] with x' = v exactly (detected once per Jacobian), the Schur system
  /// is halved to the v unknowns.
  /// blocks = 0 restores the dense LU. @throws std::invalid_argument if it does not fit.
  void setBlockStructure(int blocks);

  /// Selects the scheme (default kRodas3); takes effect at the next step.
  void setMethod(RosenbrockMethod method) noexcept;
  [[nodiscard]] RosenbrockMethod method() const noexcept { return method_; }

  /// Forgets the step-size history (the next advance() starts from `initial_step_s`). @rt
  void resetStepSize(double initial_step_s) noexcept { h_ = initial_step_s; }
  /// Step size the controller proposes for the next step [s].
  [[nodiscard]] double proposedStep() const noexcept { return h_; }
  [[nodiscard]] const RosenbrockStats& stats() const noexcept { return stats_; }
  /// True if the last factorisation used the half-size Schur system of a second-order border.
  [[nodiscard]] bool halvedBorder() const noexcept { return blocks_ > 0 && second_order_border_; }
  void resetCounters() noexcept { stats_ = {}; }

 private:
  /// One attempted step of length h from y0_; returns the error norm (inf if not finite).
  double attempt(double h) noexcept;
  /// The Rodas4 stages of attempt() after the factorisation.
  double attemptRodas4(double h) noexcept;
  /// The stages of a W-method (transformed tableau w_) after the factorisation.
  double attemptW(double h) noexcept;
  /// Weighted RMS norm of an embedded error estimate against y0_ and y1_ (inf if not finite).
  double errorNorm(const Vector& estimate) const noexcept;
  /// Factorises G = I / (h gamma) - J unless the last factorisation is of the same J and h; false if singular.
  bool factor(double h) noexcept;
  /// Factorises G = d I - J (d = 1 / (h gamma)) unconditionally; false if singular.
  bool factorG(double d) noexcept;
  /// The block-elimination part of factorG(); M > 0: the border size at compile time.
  template <int M>
  bool factorBlocks(double d) noexcept;
  /// x = G^-1 b with the last factorisation.
  void solve(const Vector& b, Vector& x) noexcept;
  /// The border part of solve(): x_m (in place) from b_m and z_. P > 0: the half border size at compile time.
  template <int P>
  void solveHalvedBorder(double* xm) const noexcept;
  void solveBorder(double* xm) const noexcept;
  /// Half border size compiled at fixed size (the whole arm's seven joint velocities).
  static constexpr int kFixedHalfBorder = 7;

  int n_ = 0;
  double rtol_ = 1e-6;
  long max_steps_ = 1000;
  double h_ = 1e-4;
  RosenbrockSystem sys_{};
  RosenbrockMethod method_ = RosenbrockMethod::kRodas3;
  RosenbrockStats stats_{};
  Vector atol_, y0_, f0_, y1_, k1_, k2_, k3_, k4_, stage_, fstage_;
  std::array<Vector, 6> ks_;  // Rodas4 and W-method stage increments
  // W-method tableau in the transformed form of attempt(): stage i at y0 + sum_j a_ij u_j,
  // G u_i = f(stage i) + sum_j (c_ij / h) u_j, y1 = y0 + sum m_j u_j, error estimate sum e_j u_j.
  struct WTableau {
    int stages = 0;
    double gamma = 0.0;
    double a[4][4] = {};
    double c[4][4] = {};
    double m[4] = {};
    double e[4] = {};
  };
  WTableau w_tab_{};
  double factored_h_ = 0.0;    // h of the factorisation in g_ / the block storage
  bool factor_valid_ = false;  // g_ is the factorisation of I/(h gamma) - jac_ at factored_h_
  Matrix jac_, g_;
  std::array<int, kMaxRosenbrockStates> pivots_{};
  // Block elimination: per-block inverse of D_k, W = D^-1 B (blocks x border), Schur S = E - C W.
  using BorderMatrix =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxRosenbrockStates, kMaxRosenbrockStates>;
  int blocks_ = 0;
  int border_ = 0;
  std::array<Eigen::Matrix4d, kMaxRosenbrockStates / kRosenbrockBlock> block_inv_{};
  BorderMatrix w_, schur_, schur_reduced_;
  bool second_order_border_ = false;  // border = [x; v] with x' = v: half-size Schur system
  double inv_d_ = 0.0;                // h gamma of the last factorisation
  Vector z_, stage_scratch_;
  std::array<int, kMaxRosenbrockStates / kRosenbrockBlock> nonzero_count_{};
  std::array<int, kMaxRosenbrockStates / kRosenbrockBlock * kMaxRosenbrockStates> nonzero_cols_{};
  // Per block: the columns (0..3) of C_k = J(border rows, block k) that hold a nonzero.
  std::array<int, kMaxRosenbrockStates / kRosenbrockBlock> c_count_{};
  std::array<int, kMaxRosenbrockStates> c_cols_{};
  bool structure_valid_ = false;  // second_order_border_, nonzero_* and c_* describe the current jac_
};

}  // namespace fullarm::plant
