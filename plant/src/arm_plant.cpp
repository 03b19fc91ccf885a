#include "fullarm/plant/arm_plant.hpp"

#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/config_error.hpp"

namespace fullarm::plant {

// ---- RAII ownership of every SUNDIALS handle (docs/sources.md, Plant 3.5) ---------------
namespace {

// Layout of the CVODES state vector for n joints: joint k's hydraulic states at
// hydraulicIndex(k, kSpool .. kPressureB) = 4k .. 4k+3, then the n joint angles, then the n
// joint velocities; 6n states in all.
constexpr int kSpool = 0;
constexpr int kSpoolRate = 1;
constexpr int kPressureA = 2;
constexpr int kPressureB = 3;
constexpr int hydraulicIndex(int k, int state) {
  return 4 * k + state;
}
constexpr int angleIndex(int n, int k) {
  return 4 * n + k;
}
constexpr int velocityIndex(int n, int k) {
  return 5 * n + k;
}
constexpr int stateSize(int n) {
  return 6 * n;
}

struct ContextDeleter {
  void operator()(SUNContext c) const noexcept { SUNContext_Free(&c); }
};
struct VectorDeleter {
  void operator()(N_Vector v) const noexcept { N_VDestroy(v); }
};
struct MatrixDeleter {
  void operator()(SUNMatrix m) const noexcept { SUNMatDestroy(m); }
};
struct LinearSolverDeleter {
  void operator()(SUNLinearSolver s) const noexcept { SUNLinSolFree(s); }
};
struct CvodeDeleter {
  void operator()(void* mem) const noexcept { CVodeFree(&mem); }
};

template <typename Handle, typename Deleter>
using Owned = std::unique_ptr<std::remove_pointer_t<Handle>, Deleter>;

void check(int flag, const char* call) {
  if (flag < 0) throw std::runtime_error(std::string("CVODES: ") + call + " failed with flag " + std::to_string(flag));
}

template <typename T>
T* checkPtr(T* p, const char* call) {
  if (p == nullptr) throw std::runtime_error(std::string("CVODES: ") + call + " returned null");
  return p;
}

constexpr int kMaxEventsPerPeriod = 64;
// Length of the configuration-time CVODES call that sets up its linear solver interface [s].
constexpr double kWarmUpTimeS = 1e-9;
// Joint count of the whole DTS arm, for which the small dense loops below are compiled at fixed size.
constexpr int kArmJoints = 7;
// First Rodas3 step after a reset [s]; the controller adapts it from there.
constexpr double kRodasInitialStep_s = 1e-4;

// Cholesky factor M = L L^T of the small SPD joint-space inertia (strict lower triangle of l,
// with 1 / L_jj on its diagonal so the solves multiply instead of divide; plain loops: at
// n <= 10 a library call's dispatch costs more than the arithmetic).
// N > 0: the size at compile time (the whole arm's 7, so that the compiler unrolls the short
// loops; the run-time bounds cost more than the arithmetic there), 0: the run-time n.
template <int N, typename Matrix>
void choleskyFactor(const Matrix& m, Matrix& l, int n_runtime) noexcept {
  const int n = N > 0 ? N : n_runtime;
  // Raw column-major storage with leading dimension n (the matrices are n x n), so that at fixed N
  // every offset is a constant.
  const double* a = m.data();
  double* f = l.data();
#pragma GCC unroll 16
  for (int j = 0; j < n; ++j) {
    double d = a[j + j * n];
#pragma GCC unroll 16
    for (int k = 0; k < j; ++k) d -= f[j + k * n] * f[j + k * n];
    const double inv = 1.0 / std::sqrt(d);
    f[j + j * n] = inv;
#pragma GCC unroll 16
    for (int i = j + 1; i < n; ++i) {
      double v = a[i + j * n];
#pragma GCC unroll 16
      for (int k = 0; k < j; ++k) v -= f[i + k * n] * f[j + k * n];
      f[i + j * n] = v * inv;
    }
  }
}

// x = M^-1 b with the factor of choleskyFactor (b and x may be the same vector).
template <int N, typename Matrix, typename Vector>
void choleskySolve(const Matrix& l, const Vector& b, Vector& x_out, int n_runtime) noexcept {
  const int n = N > 0 ? N : n_runtime;
  const double* f = l.data();
  double x[kMaxPlantJoints];
#pragma GCC unroll 16
  for (int i = 0; i < n; ++i) {
    double v = b[i];
#pragma GCC unroll 16
    for (int k = 0; k < i; ++k) v -= f[i + k * n] * x[k];
    x[i] = v * f[i + i * n];
  }
#pragma GCC unroll 16
  for (int i = n - 1; i >= 0; --i) {
    double v = x[i];
#pragma GCC unroll 16
    for (int k = i + 1; k < n; ++k) v -= f[k + i * n] * x[k];
    x[i] = v * f[i + i * n];
  }
  for (int i = 0; i < n; ++i) x_out[i] = x[i];
}

// M^-1 from the factor of choleskyFactor: column k solves M x = e_k, whose forward
// substitution is zero above row k.
template <int N, typename Matrix>
void choleskyInverse(const Matrix& l, Matrix& inv, int n_runtime) noexcept {
  const int n = N > 0 ? N : n_runtime;
  const double* f = l.data();
  double* out = inv.data();
#pragma GCC unroll 16
  for (int k = 0; k < n; ++k) {
    double x[kMaxPlantJoints];
    for (int i = 0; i < k; ++i) x[i] = 0.0;
    x[k] = f[k + k * n];
#pragma GCC unroll 16
    for (int i = k + 1; i < n; ++i) {
      double v = 0.0;
#pragma GCC unroll 16
      for (int j = k; j < i; ++j) v -= f[i + j * n] * x[j];
      x[i] = v * f[i + i * n];
    }
#pragma GCC unroll 16
    for (int i = n - 1; i >= 0; --i) {
      double v = x[i];
#pragma GCC unroll 16
      for (int j = i + 1; j < n; ++j) v -= f[j + i * n] * x[j];
      x[i] = v * f[i + i * n];
    }
    for (int i = 0; i < n; ++i) out[i + k * n] = x[i];
  }
}

// Which side of its range a joint is on: -1 below min, 0 inside, 1 above max.
signed char stopSide(const JointParams& p, double q) {
  if (p.actuator.kind == ActuatorKind::kIdealTorque) return 0;
  return q > p.max_rad ? 1 : (q < p.min_rad ? -1 : 0);
}

// Dense direct linear solver for the Newton matrix I - gamma J with Eigen's blocked,
// vectorised partial-pivoting LU in fixed-capacity storage (no heap after construction);
// several times faster than SUNDIALS' reference dense LU at the arm's 42 states.
using NewtonMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxPlantStates, kMaxPlantStates>;
using NewtonVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxPlantStates, 1>;

struct EigenLuContent {
  Eigen::PartialPivLU<NewtonMatrix> lu;
  NewtonVector rhs;
  sunindextype last_flag = 0;
};

SUNLinearSolver_Type luType(SUNLinearSolver /*S*/) {
  return SUNLINEARSOLVER_DIRECT;
}
SUNLinearSolver_ID luId(SUNLinearSolver /*S*/) {
  return SUNLINEARSOLVER_CUSTOM;
}
int luInitialize(SUNLinearSolver /*S*/) {
  return SUNLS_SUCCESS;
}

int luSetup(SUNLinearSolver S, SUNMatrix A) {
  auto* c = static_cast<EigenLuContent*>(S->content);
  const auto n = static_cast<Eigen::Index>(SM_ROWS_D(A));
  c->lu.compute(Eigen::Map<const Eigen::MatrixXd>(SM_DATA_D(A), n, n));
  // A zero pivot makes the factor singular: report it as recoverable (CVODE cuts the step).
  const double min_pivot = c->lu.matrixLU().diagonal().cwiseAbs().minCoeff();
  c->last_flag = min_pivot > 0.0 && std::isfinite(min_pivot) ? 0 : 1;
  return c->last_flag == 0 ? SUNLS_SUCCESS : SUNLS_LUFACT_FAIL;
}

int luSolve(SUNLinearSolver S, SUNMatrix /*A*/, N_Vector x, N_Vector b, sunrealtype /*tol*/) {
  auto* c = static_cast<EigenLuContent*>(S->content);
  const auto n = static_cast<Eigen::Index>(N_VGetLength(b));
  // P A = L U: x = U^-1 L^-1 P b, in place in fixed-capacity storage.
  c->rhs.noalias() = c->lu.permutationP() * Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(b), n);
  c->lu.matrixLU().template triangularView<Eigen::UnitLower>().solveInPlace(c->rhs);
  c->lu.matrixLU().template triangularView<Eigen::Upper>().solveInPlace(c->rhs);
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(x), n) = c->rhs;
  return SUNLS_SUCCESS;
}

sunindextype luLastFlag(SUNLinearSolver S) {
  return static_cast<EigenLuContent*>(S->content)->last_flag;
}

int luFree(SUNLinearSolver S) {
  if (S == nullptr) return SUNLS_SUCCESS;
  delete static_cast<EigenLuContent*>(S->content);
  S->content = nullptr;
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}

SUNLinearSolver newEigenLuSolver(SUNContext ctx, int n) {
  SUNLinearSolver S = SUNLinSolNewEmpty(ctx);
  if (S == nullptr) return nullptr;
  S->ops->gettype = luType;
  S->ops->getid = luId;
  S->ops->initialize = luInitialize;
  S->ops->setup = luSetup;
  S->ops->solve = luSolve;
  S->ops->lastflag = luLastFlag;
  S->ops->free = luFree;
  auto* content = new EigenLuContent();
  content->lu = Eigen::PartialPivLU<NewtonMatrix>(n);
  content->rhs.setZero(n);
  S->content = content;
  return S;
}

}  // namespace

// Declared in this order so they are destroyed in reverse: solver memory first, context last.
struct ArmPlant::Solver {
  Owned<SUNContext, ContextDeleter> ctx;
  Owned<N_Vector, VectorDeleter> y;
  Owned<N_Vector, VectorDeleter> abstol;
  Owned<SUNMatrix, MatrixDeleter> A;
  Owned<SUNLinearSolver, LinearSolverDeleter> ls;
  Owned<void*, CvodeDeleter> mem;
};

struct SolverCallbacks {
  static int rhs(sunrealtype /*t*/, N_Vector y, N_Vector ydot, void* user) noexcept {
    auto* plant = static_cast<ArmPlant*>(user);
    plant->evaluateRhs(N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
    return std::isfinite(N_VGetArrayPointer(ydot)[0]) ? 0 : 1;  // 1: recoverable, CVODE retries smaller
  }
  static int jac(sunrealtype /*t*/, N_Vector y, N_Vector /*fy*/, SUNMatrix J, void* user, N_Vector /*tmp1*/,
                 N_Vector /*tmp2*/, N_Vector /*tmp3*/) noexcept {
    auto* plant = static_cast<ArmPlant*>(user);
    plant->evaluateJacobian(N_VGetArrayPointer(y), SM_DATA_D(J));
    return 0;
  }
  // Two roots per joint: q - q_max and q_min - q (hard-stop contact and release).
  static int roots(sunrealtype /*t*/, N_Vector yv, sunrealtype* g, void* user) noexcept {
    const auto* plant = static_cast<const ArmPlant*>(user);
    const double* y = N_VGetArrayPointer(yv);
    const int n = plant->n_;
    for (int k = 0; k < n; ++k) {
      const JointParams& p = plant->params_[static_cast<std::size_t>(k)];
      const double q = y[angleIndex(n, k)];
      const bool ideal = p.actuator.kind == ActuatorKind::kIdealTorque;
      g[2 * k] = ideal ? -1.0 : q - p.max_rad;
      g[2 * k + 1] = ideal ? -1.0 : p.min_rad - q;
    }
    return 0;
  }
  // Rodas3 system: f(y), and J(y) with f(y) from the same pass.
  static void rodasRhs(void* user, const double* y, double* ydot) noexcept {
    static_cast<ArmPlant*>(user)->evaluateRhs(y, ydot);
  }
  static void rodasJacobian(void* user, const double* y, double* ydot, double* jac) noexcept {
    auto* plant = static_cast<ArmPlant*>(user);
    // Rodas3 keeps its Jacobian storage to itself (zeroed at configure): only the structural
    // nonzeros need writing. Evaluates f(y) into ydot_scratch_ first.
    plant->jacobianEntries(y, jac);
    std::copy_n(plant->ydot_scratch_, stateSize(plant->n_), ydot);
  }
  static void error(int code, const char* module, const char* function, char* msg, void* user) noexcept {
    auto* plant = static_cast<ArmPlant*>(user);
    std::snprintf(plant->error_, sizeof(plant->error_), "%s %s (%d): %s", module, function, code, msg);
  }
};

PlantCommand PlantCommand::zero(int n) {
  PlantCommand c;
  c.command = JointVector::Zero(n);
  c.tau_user_nm = JointVector::Zero(n);
  c.tau_contact_nm = JointVector::Zero(n);
  return c;
}

ArmPlant::ArmPlant() = default;
ArmPlant::~ArmPlant() = default;

namespace {

// Adds a point mass to a link (parallel-axis theorem), keeping the inertia about the new COM.
void mergePointMass(arm::LinkInertial& link, double mass_kg, const Eigen::Vector3d& p_L) {
  if (mass_kg <= 0.0) return;
  const double m0 = link.mass_kg;
  const double m = m0 + mass_kg;
  const Eigen::Vector3d com = (m0 * link.com_m + mass_kg * p_L) / m;
  auto shift = [](double mass, const Eigen::Vector3d& d) {
    return Eigen::Matrix3d(mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose()));
  };
  link.inertia_com_kgm2 = link.inertia_com_kgm2 + shift(m0, link.com_m - com) + shift(mass_kg, p_L - com);
  link.com_m = com;
  link.mass_kg = m;
}

}  // namespace

void ArmPlant::configure(const arm::ArmModel& model, const std::vector<JointParams>& joints,
                         const Eigen::VectorXd& posture, const UserArmParams& user, const SolverOptions& options,
                         std::uint64_t seed) {
  if (joints.empty() || static_cast<int>(joints.size()) > kMaxPlantJoints) {
    throw core::ConfigError(model.source, "joints", "expected 1 to " + std::to_string(kMaxPlantJoints) + " joints");
  }
  if (posture.size() != model.numJoints()) {
    throw core::ConfigError(model.source, "posture", "expected " + std::to_string(model.numJoints()) + " joint angles");
  }
  std::vector<int> active;
  for (const JointParams& p : joints) {
    const int index = model.jointIndex(p.name);
    if (index < 0) throw core::ConfigError(model.source, "joints", "unknown joint name '" + p.name + "'");
    if (std::find(active.begin(), active.end(), index) != active.end()) {
      throw core::ConfigError(model.source, "joints", "joint '" + p.name + "' listed twice");
    }
    validateJointParams(p, {}, p.name);
    active.push_back(index);
  }
  if (user.enabled && (user.link < 0 || user.link >= model.numJoints())) {
    throw core::ConfigError(model.source, "user_arm.link", "cuff link index out of range");
  }
  params_ = joints;
  selection_ = arm::JointSelection(model.numJoints(), active);
  n_ = static_cast<int>(joints.size());
  user_ = user;
  model_ = std::make_unique<arm::ArmModel>(model);
  if (user.enabled)
    mergePointMass(model_->joints[static_cast<std::size_t>(user.link)].inertial, user.mass_kg, user.point_L);
  data_ = std::make_unique<arm::ArmData>(*model_);
  posture_ = posture;
  single_axis_ = n_ == 1;
  single_axis_cuff_ = false;
  // The per-step dynamics runs on the arm reduced to the active joints: every locked link
  // (the hand, and the arm joints a partial plant does not drive) merged into the body that
  // carries it (arm/rigid_body_dynamics.hpp; equal to fullarm::arm's Newton-Euler to 1e-12, tested).
  reduced_ = std::make_unique<arm::RigidBodyModel>(arm::reduceArmModel(*model_, active, posture));
  reduced_data_ = std::make_unique<arm::RigidBodyData>();
  cuff_point_ = user.enabled ? arm::reducePoint(*model_, active, posture, user.link, user.point_L) : arm::BodyPoint{};
  if (single_axis_) {
    // One joint turning with the rest of the arm locked: a rigid body about a fixed axis, so
    // the inertia is constant and gravity is a cos q + b sin q (exact; evaluated once here).
    const int i = selection_.modelIndex(0);
    const arm::SingleAxisLoad axis = arm::computeSingleAxisLoad(*model_, i, posture);
    load_.inertia_kgm2 = axis.inertia_kgm2;
    load_.gravity_cos_nm = axis.gravity_cos_nm;
    load_.gravity_sin_nm = axis.gravity_sin_nm;
    Eigen::VectorXd q = posture;
    q[i] = 0.0;
    arm::computeForwardKinematics(*model_, *data_, q);
    axis_W_ = data_->z_W[static_cast<std::size_t>(i)];
    origin_W_ = data_->o_W[static_cast<std::size_t>(i)];
    if (user.enabled && arm::jointMovesLink(*model_, i, user.link)) {
      single_axis_cuff_ = true;
      cuff0_W_ = arm::pointInWorld(*data_, user.link, user.point_L);
    }
  }
  allocate(options, seed);
}

void ArmPlant::configure(const JointParams& joint, const RigidLoad& load, const SolverOptions& options,
                         std::uint64_t seed) {
  validateJointParams(joint, {}, joint.name);
  if (!(load.inertia_kgm2 > 0.0) && joint.actuator.inertia_kgm2 <= 0.0) {
    throw core::ConfigError({}, "load.inertia_kgm2", "expected a positive inertia");
  }
  params_ = {joint};
  selection_ = {};
  n_ = 1;
  user_ = {};
  model_.reset();
  data_.reset();
  reduced_.reset();
  reduced_data_.reset();
  single_axis_ = true;
  single_axis_cuff_ = false;
  load_ = load;
  allocate(options, seed);
}

void ArmPlant::allocate(const SolverOptions& options, std::uint64_t seed) {
  options_ = options;
  seed_ = seed;
  cmd_ = PlantCommand::zero(n_);
  last_cmd_ = cmd_;
  qdd_ = tau_cell_ = tau_hyd_ = tau_act_ = h_ = tau_cuff_ = JointVector::Zero(n_);
  mass_.setZero(n_, n_);
  mass_inv_.setZero(n_, n_);
  chol_.setZero(n_, n_);
  cuff_jac_.setZero(3, n_);
  stroke_.clear();
  for (const JointParams& p : params_) stroke_.push_back(strokeRange(p));
  lever_offset_.clear();
  for (const JointParams& p : params_) lever_offset_.push_back(leverOffsetSinCos(p.actuator));
  volumes_.assign(static_cast<std::size_t>(n_), ChamberVolumes{});
  terms_.assign(static_cast<std::size_t>(n_), JointTerms{});
  air_root_.clear();
  for (const JointParams& p : params_) air_root_.push_back(airRoot(p.fluid));
  sensor_state_.assign(static_cast<std::size_t>(n_), JointSensorState{});
  measured_.assign(static_cast<std::size_t>(n_), JointMeasurement{});

  const auto N = static_cast<sunindextype>(stateSize(n_));
  auto s = std::make_unique<Solver>();
  SUNContext ctx = nullptr;
  check(SUNContext_Create(nullptr, &ctx), "SUNContext_Create");
  s->ctx.reset(ctx);
  s->y.reset(checkPtr(N_VNew_Serial(N, ctx), "N_VNew_Serial"));
  s->abstol.reset(checkPtr(N_VNew_Serial(N, ctx), "N_VNew_Serial"));
  N_VConst(0.0, s->y.get());
  double* atol = N_VGetArrayPointer(s->abstol.get());
  for (int k = 0; k < n_; ++k) {
    atol[hydraulicIndex(k, kSpool)] = options.atol_spool;
    atol[hydraulicIndex(k, kSpoolRate)] = options.atol_spool_rate_per_s;
    atol[hydraulicIndex(k, kPressureA)] = options.atol_pressure_pa;
    atol[hydraulicIndex(k, kPressureB)] = options.atol_pressure_pa;
    atol[angleIndex(n_, k)] = options.atol_angle_rad;
    atol[velocityIndex(n_, k)] = options.atol_velocity_radps;
  }
  s->mem.reset(checkPtr(CVodeCreate(CV_BDF, ctx), "CVodeCreate"));
  void* mem = s->mem.get();
  check(CVodeInit(mem, &SolverCallbacks::rhs, 0.0, s->y.get()), "CVodeInit");
  check(CVodeSetUserData(mem, this), "CVodeSetUserData");
  check(CVodeSetErrHandlerFn(mem, &SolverCallbacks::error, this), "CVodeSetErrHandlerFn");
  check(CVodeSVtolerances(mem, options.rtol, s->abstol.get()), "CVodeSVtolerances");
  s->A.reset(checkPtr(SUNDenseMatrix(N, N, ctx), "SUNDenseMatrix"));
  s->ls.reset(checkPtr(newEigenLuSolver(ctx, static_cast<int>(N)), "SUNLinSolNewEmpty"));
  check(CVodeSetLinearSolver(mem, s->ls.get(), s->A.get()), "CVodeSetLinearSolver");
  if (options.jacobian == JacobianKind::kAnalytic) check(CVodeSetJacFn(mem, &SolverCallbacks::jac), "CVodeSetJacFn");
  check(CVodeSetMaxNumSteps(mem, options.max_steps_per_period), "CVodeSetMaxNumSteps");
  check(CVodeRootInit(mem, 2 * n_, &SolverCallbacks::roots), "CVodeRootInit");
  check(CVodeSetNoInactiveRootWarn(mem), "CVodeSetNoInactiveRootWarn");
  // The first CVode call after CVodeInit sets up the linear solver interface, which allocates a
  // copy of the Jacobian matrix (cvLsInitialize clones it once). Make that call here, where
  // allocation is allowed, so that step() never allocates: one internal step from the zero
  // state, whose result is discarded. Every run starts with CVodeReInit (reset() requests it),
  // which keeps the copy.
  {
    double t_reached = 0.0;
    check(CVodeSetStopTime(mem, kWarmUpTimeS), "CVodeSetStopTime");
    (void)CVode(mem, kWarmUpTimeS, s->y.get(), &t_reached, CV_ONE_STEP);
    N_VConst(0.0, s->y.get());
    error_[0] = '\0';
  }
  solver_ = std::move(s);
  rodas_.reset();
  if (options.integrator == IntegratorKind::kRodas3 || options.integrator == IntegratorKind::kRodas4 ||
      options.integrator == IntegratorKind::kRos34pw2) {
    rodas_ = std::make_unique<RosenbrockIntegrator>();
    rodas_->setMethod(options.integrator == IntegratorKind::kRodas4     ? RosenbrockMethod::kRodas4
                      : options.integrator == IntegratorKind::kRos34pw2 ? RosenbrockMethod::kRos34pw2
                                                                        : RosenbrockMethod::kRodas3);
    rodas_->configure(static_cast<int>(N), atol, options.rtol, options.max_steps_per_period,
                      {&SolverCallbacks::rodasRhs, &SolverCallbacks::rodasJacobian, this});
    // Joint k's hydraulic states couple to other joints only through q and qd, except in
    // torque-loop mode, where the load-cell feedback sees every joint's pressures through M^-1.
    bool blocks = true;
    for (const JointParams& p : params_) blocks = blocks && p.input_mode == InputMode::kValveVoltage;
    // (one joint: a dense 6 x 6 LU is cheaper than the block elimination)
    rodas_->setBlockStructure(blocks && n_ > 1 ? n_ : 0);
  }
  stop_side_.assign(static_cast<std::size_t>(n_), 0);
  // Rodas3 on the whole arm takes the rigid-body gradients into its Jacobian (see
  // rigidBodyGradients); one joint's load is exact already (a fixed axis).
  rigid_body_gradients_ = rodas_ != nullptr && !single_axis_;
  rigid_dq_.setZero(n_, n_);
  rigid_dqd_.setZero(n_, n_);
  rigid_tau_.setZero(n_);
  q_.setZero(n_);
  qd_.setZero(n_);
  mechanics_q_.setZero(n_);
  mechanics_qd_.setZero(n_);
  mechanics_valid_ = false;
  zero_.setZero(n_);
  reset();
}

void ArmPlant::reset() {
  std::vector<JointState> initial(static_cast<std::size_t>(n_));
  for (int k = 0; k < n_; ++k) {
    const JointParams& p = params_[static_cast<std::size_t>(k)];
    JointState& s = initial[static_cast<std::size_t>(k)];
    s.p_a_pa = s.p_b_pa = 0.5 * (p.supply_pressure_pa + p.return_pressure_pa);
    s.q_rad = modelIndex(k) >= 0 ? posture_[modelIndex(k)] : std::clamp(0.0, p.min_rad, p.max_rad);
  }
  reset(initial);
}

void ArmPlant::reset(const std::vector<JointState>& initial) {
  if (!solver_) throw std::logic_error("ArmPlant::reset before configure");
  if (static_cast<int>(initial.size()) != n_) throw std::invalid_argument("ArmPlant::reset: one state per joint");
  double* y = N_VGetArrayPointer(solver_->y.get());
  for (int k = 0; k < n_; ++k) {
    const JointState& s = initial[static_cast<std::size_t>(k)];
    y[hydraulicIndex(k, kSpool)] = s.spool;
    y[hydraulicIndex(k, kSpoolRate)] = s.spool_rate_per_s;
    y[hydraulicIndex(k, kPressureA)] = s.p_a_pa;
    y[hydraulicIndex(k, kPressureB)] = s.p_b_pa;
    y[angleIndex(n_, k)] = s.q_rad;
    y[velocityIndex(n_, k)] = s.qd_radps;
  }
  t_ = 0.0;
  stats_ = stats_base_ = {};
  cmd_ = last_cmd_ = PlantCommand::zero(n_);
  need_reinit_ = true;
  cvodes_counters_stale_ = true;  // CVODES still counts the previous run until its next re-init
  error_[0] = '\0';
  if (rodas_) {
    rodas_->resetStepSize(kRodasInitialStep_s);
    rodas_->resetCounters();
  }
  for (int k = 0; k < n_; ++k)
    stop_side_[static_cast<std::size_t>(k)] = stopSide(params_[static_cast<std::size_t>(k)], y[angleIndex(n_, k)]);
  mechanics_valid_ = false;  // (the cuff anchor below moves, and the kinematics are overwritten)
  rigid_derivatives_stale_ = true;
  if (reduced_ && user_.enabled) {
    // The cuff spring rests where the cuff is at the initial state.
    for (int k = 0; k < n_; ++k) {
      q_[k] = y[angleIndex(n_, k)];
      qd_[k] = 0.0;
    }
    arm::computeRigidBodyKinematics(*reduced_, *reduced_data_, q_, qd_);
    cuff_anchor_W_ = cuff_point_.body < 0 ? cuff_point_.p_B
                                          : arm::bodyPointInWorld(*reduced_data_, cuff_point_.body, cuff_point_.p_B);
  }
  noise_.reseed(seed_);
  pressure_noise_.reseed(seed_ ^ kPressureNoiseStream);
  for (JointSensorState& s : sensor_state_) s = {};
  initialiseSensors();
}

void ArmPlant::initialiseSensors() noexcept {
  evaluateRhs(N_VGetArrayPointer(solver_->y.get()), ydot_scratch_);
  const double* y = N_VGetArrayPointer(solver_->y.get());
  for (int k = 0; k < n_; ++k) {
    measured_[static_cast<std::size_t>(k)] =
        sampleJointSensors(params_[static_cast<std::size_t>(k)], sensor_state_[static_cast<std::size_t>(k)], noise_,
                           y[angleIndex(n_, k)], tau_cell_[k], 0.0);
    samplePressureSensors(params_[static_cast<std::size_t>(k)], pressure_noise_, y[hydraulicIndex(k, kPressureA)],
                          y[hydraulicIndex(k, kPressureB)], measured_[static_cast<std::size_t>(k)]);
  }
}

JointState ArmPlant::state(int k) const noexcept {
  const double* y = N_VGetArrayPointer(solver_->y.get());
  return {y[hydraulicIndex(k, kSpool)],
          y[hydraulicIndex(k, kSpoolRate)],
          y[hydraulicIndex(k, kPressureA)],
          y[hydraulicIndex(k, kPressureB)],
          y[angleIndex(n_, k)],
          y[velocityIndex(n_, k)]};
}

Eigen::VectorXd ArmPlant::stateVector() const {
  const double* y = N_VGetArrayPointer(solver_->y.get());
  return Eigen::Map<const Eigen::VectorXd>(y, stateSize(n_));
}

void ArmPlant::singleAxisCuff(double q, double qd, double& tau, double& dtau_dq, double& dtau_dqd) const noexcept {
  // Cuff point turning rigidly about the joint axis: p(q) = o + Rot(z, q)(p0 - o).
  const Eigen::Vector3d r = Eigen::AngleAxisd(q, axis_W_) * (cuff0_W_ - origin_W_);
  const Eigen::Vector3d p = origin_W_ + r;
  const Eigen::Vector3d jac = axis_W_.cross(r);  // dp/dq
  const Eigen::Vector3d f = -user_.stiffness_n_per_m * (p - cuff_anchor_W_) - user_.damping_ns_per_m * jac * qd;
  tau = jac.dot(f);
  // d/dq of jac . f with d(jac)/dq = z x jac (and jac . (z x jac) = 0).
  dtau_dq = axis_W_.cross(jac).dot(f) - user_.stiffness_n_per_m * jac.squaredNorm();
  dtau_dqd = -user_.damping_ns_per_m * jac.squaredNorm();
}

// Rigid-body part: fills mass_ (incl. actuator inertias), mass_inv_, h_ (C qd + g) and
// tau_cuff_, cuff_jac_ for the state y.
// H14: joint mechanics (reports/equations.md).
void ArmPlant::mechanics(const double* y) noexcept {
  const int n = n_;
  if (single_axis_) {
    const double q = y[angleIndex(n, 0)];
    const double qd = y[velocityIndex(n, 0)];
    mass_(0, 0) = load_.inertia_kgm2 + params_[0].actuator.inertia_kgm2;
    mass_inv_(0, 0) = 1.0 / mass_(0, 0);
    single_axis_sincos_ = {std::sin(q), std::cos(q)};  // shared with the cylinder geometry
    h_[0] = load_.gravity_cos_nm * single_axis_sincos_.cos + load_.gravity_sin_nm * single_axis_sincos_.sin;
    tau_cuff_[0] = 0.0;
    cuff_jac_.setZero();
    if (single_axis_cuff_) {
      double k = 0.0;
      double b = 0.0;
      singleAxisCuff(q, qd, tau_cuff_[0], k, b);
    }
    return;
  }
  for (int k = 0; k < n; ++k) {
    q_[k] = y[angleIndex(n, k)];
    qd_[k] = y[velocityIndex(n, k)];
  }
  // Everything below depends on (q, qd) only: at the state of the previous call (the period's
  // end, sampled by sampleOutputs() and then the next period's first Jacobian) it is reused.
  if (mechanics_valid_ && q_ == mechanics_q_ && qd_ == mechanics_qd_) return;
  // Newton-Euler on the reduced arm: h = C(q, qd) qd + g(q) (ID at qdd = 0), then M(q) by
  // composite rigid bodies (arm/rigid_body_dynamics.hpp, R1-R5).
  arm::RigidBodyData& d = *reduced_data_;
  arm::computeRigidBodyKinematics(*reduced_, d, q_, qd_);
  arm::computeRigidBodyInverseDynamics(reduced_->tree, d, zero_, h_);
  arm::computeRigidBodyMassMatrix(reduced_->tree, d, mass_);
  for (int a = 0; a < n; ++a) mass_(a, a) += params_[static_cast<std::size_t>(a)].actuator.inertia_kgm2;
  if (user_.enabled && cuff_point_.body >= 0) {
    // Cuff spring and damper through the point Jacobian: column k = z_k x (p - o_k) for the
    // joints that move the cuff's body.
    const auto body = static_cast<std::size_t>(cuff_point_.body);
    const Eigen::Vector3d p = arm::bodyPointInWorld(d, cuff_point_.body, cuff_point_.p_B);
    for (int k = 0; k < n; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      cuff_jac_.col(k) = reduced_->tree.supports[kk][body] ? Eigen::Vector3d(d.s[kk].top.cross(p - d.o_W[kk]))
                                                           : Eigen::Vector3d::Zero();
    }
    const Eigen::Vector3d v = cuff_jac_ * qd_;
    const Eigen::Vector3d f = -user_.stiffness_n_per_m * (p - cuff_anchor_W_) - user_.damping_ns_per_m * v;
    tau_cuff_.noalias() = cuff_jac_.transpose() * f;
  } else {
    cuff_jac_.setZero();
    tau_cuff_.setZero();
  }
  mechanics_q_ = q_;
  mechanics_qd_ = qd_;
  mechanics_valid_ = true;
}

// H12: spool dynamics and torque loop; H13: chamber continuity; H15: load-cell torque (reports/equations.md).
void ArmPlant::evaluateRhs(const double* y, double* ydot) noexcept {
  evaluateTorques(y);
  evaluateRates(y, ydot);
}

void ArmPlant::evaluateTorques(const double* y) noexcept {
  const int n = n_;
  mechanics(y);
  // Actuator torques: hydraulic (virtual work tau = p_a dV_a/dq + p_b dV_b/dq), friction, stops.
  for (int k = 0; k < n; ++k) {
    const JointParams& p = params_[static_cast<std::size_t>(k)];
    const double q = y[angleIndex(n, k)];
    const double qd = y[velocityIndex(n, k)];
    if (p.actuator.kind == ActuatorKind::kIdealTorque) {
      tau_hyd_[k] = cmd_.command[k];
      tau_act_[k] = tau_hyd_[k];
      continue;
    }
    // sin q, cos q from the rigid-body pass above (mechanics()).
    const SinCos q_sincos = single_axis_ ? single_axis_sincos_
                                         : SinCos{reduced_data_->sin_q[static_cast<std::size_t>(k)],
                                                  reduced_data_->cos_q[static_cast<std::size_t>(k)]};
    const ChamberVolumes& v = volumes_[static_cast<std::size_t>(k)] = chamberVolumes(
        p, stroke_[static_cast<std::size_t>(k)], q, q_sincos, lever_offset_[static_cast<std::size_t>(k)]);
    JointTerms& c = terms_[static_cast<std::size_t>(k)];
    c.friction = frictionTorque(p.friction, qd);
    c.stop = hardStopTorque(p, q, qd);
    tau_hyd_[k] = y[hydraulicIndex(k, kPressureA)] * v.dva_dq + y[hydraulicIndex(k, kPressureB)] * v.dvb_dq;
    tau_act_[k] = tau_hyd_[k] - c.friction.value + c.stop.torque_nm;
  }
  // M qdd = tau_act + tau_user + tau_contact + tau_cuff - (C qd + g)   (rigid body, Craig 6.5)
  JointVector rhs = tau_act_ + cmd_.tau_user_nm + cmd_.tau_contact_nm + tau_cuff_ - h_;
  if (n == 1) {
    qdd_[0] = rhs[0] * mass_inv_(0, 0);
  } else {
    if (n == kArmJoints) {
      choleskyFactor<kArmJoints>(mass_, chol_, n);
      choleskySolve<kArmJoints>(chol_, rhs, qdd_, n);
    } else {
      choleskyFactor<0>(mass_, chol_, n);
      choleskySolve<0>(chol_, rhs, qdd_, n);
    }
  }
  // Load cell between the actuator side and the link: tau_cell = tau_act - J_act qdd.
  for (int k = 0; k < n; ++k)
    tau_cell_[k] = tau_act_[k] - params_[static_cast<std::size_t>(k)].actuator.inertia_kgm2 * qdd_[k];
}

void ArmPlant::evaluateRates(const double* y, double* ydot) noexcept {
  const int n = n_;
  for (int k = 0; k < n; ++k) {
    const JointParams& p = params_[static_cast<std::size_t>(k)];
    const double qd = y[velocityIndex(n, k)];
    ydot[angleIndex(n, k)] = qd;
    ydot[velocityIndex(n, k)] = qdd_[k];
    if (p.actuator.kind == ActuatorKind::kIdealTorque) {
      ydot[hydraulicIndex(k, kSpool)] = ydot[hydraulicIndex(k, kSpoolRate)] = ydot[hydraulicIndex(k, kPressureA)] =
          ydot[hydraulicIndex(k, kPressureB)] = 0.0;
      continue;
    }
    // Spool (docs/sources.md, Plant 1.1): xv'' = w^2 (u - xv) - 2 zeta w xv'.
    const double volts = p.input_mode == InputMode::kValveVoltage
                             ? cmd_.command[k]
                             : p.torque_loop.gain_v_per_nm * (cmd_.command[k] - tau_cell_[k]);
    const double u = std::clamp(p.valve.amplifier_gain_per_v * volts, -1.0, 1.0);
    const double w = 2.0 * std::numbers::pi * p.valve.natural_frequency_hz;
    const double xv = y[hydraulicIndex(k, kSpool)];
    const double vv = y[hydraulicIndex(k, kSpoolRate)];
    ydot[hydraulicIndex(k, kSpool)] = vv;
    ydot[hydraulicIndex(k, kSpoolRate)] = w * w * (u - xv) - 2.0 * p.valve.damping_ratio * w * vv;
    // Chambers (docs/sources.md, Plant 1.3): p' = beta(p)/V (Q_in - leakage - dV/dt).
    const double pa = y[hydraulicIndex(k, kPressureA)];
    const double pb = y[hydraulicIndex(k, kPressureB)];
    JointTerms& c = terms_[static_cast<std::size_t>(k)];
    c.flows = valveFlows(p, xv, pa, pb);
    const ValveFlows& f = c.flows;
    const ChamberVolumes& v = volumes_[static_cast<std::size_t>(k)];
    const double qi = p.chambers.internal_leakage_m3ps_per_pa * (pa - pb);
    const double ce = p.chambers.external_leakage_m3ps_per_pa;
    const double air_root = air_root_[static_cast<std::size_t>(k)];
    c.beta_a = effectiveBulkModulus(p.fluid, pa, air_root);
    c.beta_b = effectiveBulkModulus(p.fluid, pb, air_root);
    c.check_a = checkValveFlow(p, pa);
    c.check_b = checkValveFlow(p, pb);
    ydot[hydraulicIndex(k, kPressureA)] =
        c.beta_a.value / v.v_a_m3 * (f.q_a_m3ps + c.check_a.value - qi - ce * pa - v.dva_dq * qd);
    ydot[hydraulicIndex(k, kPressureB)] =
        c.beta_b.value / v.v_b_m3 * (f.q_b_m3ps + c.check_b.value + qi - ce * pb - v.dvb_dq * qd);
  }
}

void ArmPlant::evaluateJacobian(const double* y, double* Jdata) noexcept {
  const int N = stateSize(n_);
  std::fill_n(Jdata, static_cast<std::size_t>(N) * static_cast<std::size_t>(N), 0.0);
  rigid_derivatives_stale_ = true;  // the public Jacobian is always exact at y
  jacobianEntries(y, Jdata);
}

// Writes every structurally nonzero entry of J (the others must already be zero, as they stay
// between calls on the same matrix).
void ArmPlant::jacobianEntries(const double* y, double* Jdata) noexcept {
  using JointMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxPlantJoints, kMaxPlantJoints>;
  const int n = n_;
  const int N = stateSize(n);
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxPlantStates, kMaxPlantStates>> J(Jdata, N, N);
  // Reuse the RHS pass for M, tau_cell, qdd and the chamber volumes at this state.
  evaluateRhs(y, ydot_scratch_);
  if (n == 1) {
    mass_inv_(0, 0) = 1.0 / mass_(0, 0);
  } else {
    // M^-1 from the factor of the evaluateRhs() pass above.
    if (n == kArmJoints) {
      choleskyInverse<kArmJoints>(chol_, mass_inv_, n);
    } else {
      choleskyInverse<0>(chol_, mass_inv_, n);
    }
  }
  // d(generalised torque)/dy: joint k's actuator torque depends on its own p_a, p_b, q, qd
  // (t_pa, t_pb, and the diagonals of Tq, Tqd); the cuff spring/damper and the single-axis
  // gravity add to the q and qd blocks Tq, Tqd (n x n).
  JointVector t_pa = JointVector::Zero(n);
  JointVector t_pb = JointVector::Zero(n);
  JointVector tact_q = JointVector::Zero(n);
  JointVector tact_qd = JointVector::Zero(n);
  for (int k = 0; k < n; ++k) {
    const JointParams& p = params_[static_cast<std::size_t>(k)];
    if (p.actuator.kind == ActuatorKind::kIdealTorque) continue;
    const ChamberVolumes& v = volumes_[static_cast<std::size_t>(k)];
    const JointTerms& c = terms_[static_cast<std::size_t>(k)];
    t_pa[k] = v.dva_dq;
    t_pb[k] = v.dvb_dq;
    tact_q[k] =
        y[hydraulicIndex(k, kPressureA)] * v.d2va_dq2 + y[hydraulicIndex(k, kPressureB)] * v.d2vb_dq2 + c.stop.d_dq;
    tact_qd[k] = -c.friction.slope + c.stop.d_dqd;
  }
  // Diagonal q and qd partials of the generalised torque (actuator, and the single-axis gravity
  // and cuff), plus the cuff's coupling blocks on the whole arm.
  JointVector diag_q = tact_q;
  JointVector diag_qd = tact_qd;
  const bool coupled = !single_axis_ && user_.enabled;
  JointMatrix cuff_q;
  JointMatrix cuff_qd;
  if (single_axis_) {
    const double q = y[angleIndex(n, 0)];
    diag_q[0] -= -load_.gravity_cos_nm * std::sin(q) + load_.gravity_sin_nm * std::cos(q);
    if (single_axis_cuff_) {
      double tau = 0.0;
      double dq = 0.0;
      double dqd = 0.0;
      singleAxisCuff(q, y[velocityIndex(n, 0)], tau, dq, dqd);
      diag_q[0] += dq;
      diag_qd[0] += dqd;
    }
  } else if (coupled) {
    // Cuff: d(J^T f)/dq ~ -J^T K J, d/dqd = -J^T B J (rigid-body q gradients of M, C, g omitted:
    // a modified-Newton matrix; the solution accuracy is set by the tolerances, not by it).
    cuff_q.noalias() = -user_.stiffness_n_per_m * cuff_jac_.transpose() * cuff_jac_;
    cuff_qd.noalias() = -user_.damping_ns_per_m * cuff_jac_.transpose() * cuff_jac_;
  }
  // qdd = M^-1 tau: d qdd_i / d p_a(k) = Minv(i, k) t_pa(k), etc.
  for (int k = 0; k < n; ++k) {
    J(angleIndex(n, k), velocityIndex(n, k)) = 1.0;
    for (int i = 0; i < n; ++i) {
      const int row = velocityIndex(n, i);
      const double minv = mass_inv_(i, k);
      J(row, hydraulicIndex(k, kPressureA)) = minv * t_pa[k];
      J(row, hydraulicIndex(k, kPressureB)) = minv * t_pb[k];
      double dq = minv * diag_q[k];
      double dqd = minv * diag_qd[k];
      if (coupled) {
        dq += mass_inv_.row(i).dot(cuff_q.col(k));
        dqd += mass_inv_.row(i).dot(cuff_qd.col(k));
      }
      J(row, angleIndex(n, k)) = dq;
      J(row, velocityIndex(n, k)) = dqd;
    }
  }
  if (rigid_body_gradients_) rigidBodyGradients(y, J.data(), N);
  for (int k = 0; k < n; ++k) {
    const JointParams& p = params_[static_cast<std::size_t>(k)];
    if (p.actuator.kind == ActuatorKind::kIdealTorque) continue;
    const double qd = y[velocityIndex(n, k)];
    const double pa = y[hydraulicIndex(k, kPressureA)];
    const double pb = y[hydraulicIndex(k, kPressureB)];
    const double w = 2.0 * std::numbers::pi * p.valve.natural_frequency_hz;
    const int S = hydraulicIndex(k, kSpool);
    const int V = hydraulicIndex(k, kSpoolRate);
    const int A = hydraulicIndex(k, kPressureA);
    const int B = hydraulicIndex(k, kPressureB);
    const int Q = angleIndex(n, k);
    const int W = velocityIndex(n, k);
    J(S, V) = 1.0;
    if (p.input_mode == InputMode::kTorqueLoop) {
      // The whole row is assigned (its pattern depends on the valve saturation).
      for (int c = 0; c < N; ++c) J(V, c) = 0.0;
    }
    J(V, S) = -w * w;
    J(V, V) = -2.0 * p.valve.damping_ratio * w;
    if (p.input_mode == InputMode::kTorqueLoop) {
      const double volts = p.torque_loop.gain_v_per_nm * (cmd_.command[k] - tau_cell_[k]);
      const double u = p.valve.amplifier_gain_per_v * volts;
      if (u > -1.0 && u < 1.0) {
        const double g = w * w * p.valve.amplifier_gain_per_v * p.torque_loop.gain_v_per_nm;
        // d tau_cell / dy = d tau_act / dy - J_act d qdd_k / dy (row W of J is d qdd_k / dy)
        for (int c = 0; c < N; ++c) J(V, c) += g * p.actuator.inertia_kgm2 * J(W, c);
        J(V, A) -= g * t_pa[k];
        J(V, B) -= g * t_pb[k];
        J(V, Q) -= g * tact_q[k];
        J(V, W) -= g * tact_qd[k];
      }
    }
    // Flows, bulk moduli and check valves at y, from the evaluateRhs() pass above.
    const JointTerms& c = terms_[static_cast<std::size_t>(k)];
    const ValveFlows& f = c.flows;
    const ChamberVolumes& v = volumes_[static_cast<std::size_t>(k)];
    const double ci = p.chambers.internal_leakage_m3ps_per_pa;
    const double ce = p.chambers.external_leakage_m3ps_per_pa;
    const ValueSlope& ba = c.beta_a;
    const ValueSlope& bb = c.beta_b;
    const ValueSlope& cv_a = c.check_a;
    const ValueSlope& cv_b = c.check_b;
    const double fa = f.q_a_m3ps + cv_a.value - ci * (pa - pb) - ce * pa - v.dva_dq * qd;
    const double fb = f.q_b_m3ps + cv_b.value + ci * (pa - pb) - ce * pb - v.dvb_dq * qd;
    const double ka = ba.value / v.v_a_m3;
    const double kb = bb.value / v.v_b_m3;
    J(A, S) = ka * f.dqa_dx;
    J(A, A) = ba.slope / v.v_a_m3 * fa + ka * (f.dqa_dpa + cv_a.slope - ci - ce);
    J(A, B) = ka * ci;
    J(A, Q) = -ka * fa * v.dva_dq / v.v_a_m3 - ka * v.d2va_dq2 * qd;
    J(A, W) = -ka * v.dva_dq;
    J(B, S) = kb * f.dqb_dx;
    J(B, B) = bb.slope / v.v_b_m3 * fb + kb * (f.dqb_dpb + cv_b.slope - ci - ce);
    J(B, A) = kb * ci;
    J(B, Q) = -kb * fb * v.dvb_dq / v.v_b_m3 - kb * v.d2vb_dq2 * qd;
    J(B, W) = -kb * v.dvb_dq;
  }
}

// The configuration and velocity gradients of the rigid-body dynamics that the analytic
// Jacobian leaves out: M qdd = tau - h(q, qd) gives M d qdd/dq = d tau/dq - d ID/dq and
// M d qdd/dqd = d tau/dqd - d ID/dqd, with ID(q, qd, a) = M(q) a + h(q, qd) taken at a = qdd,
// from the analytic derivatives of the reduced Newton-Euler (arm/rigid_body_dynamics.hpp, R6-R8; one
// pass, exact). Subtracts M^-1 d ID into the qd rows of J (column-major, leading dimension
// ld). Rodas3 needs them: without them a Rosenbrock method drops to order one on the arm's slow
// mechanics and its error estimate no longer sees the error. Uses the kinematics, qdd_ and
// mass_inv_ of the evaluateRhs() pass at y that jacobianEntries() has just run.
// R9: rigid-body block of the Newton Jacobian (reports/equations.md).
void ArmPlant::rigidBodyGradients(const double* /*y*/, double* Jdata, int ld) noexcept {
  const int n = n_;
  if (rigid_derivatives_stale_ || !options_.rigid_derivatives_once_per_period) {
    arm::computeRigidBodyInverseDynamicsDerivatives(reduced_->tree, *reduced_data_, qdd_, rigid_tau_, rigid_dq_,
                                                    rigid_dqd_);
    rigid_derivatives_stale_ = false;
  }
  // J(qd rows, q and qd columns) -= M^-1 [d ID/dq, d ID/dqd] (plain loops: at n = 7 a general
  // matrix product's dispatch costs more than the arithmetic).
  if (n == kArmJoints) {
    subtractMinvTimesDerivatives<kArmJoints>(Jdata, ld);
  } else {
    subtractMinvTimesDerivatives<0>(Jdata, ld);
  }
}

template <int N>
void ArmPlant::subtractMinvTimesDerivatives(double* Jdata, int ld) const noexcept {
  const int n = N > 0 ? N : n_;
  const double* minv = mass_inv_.data();  // column-major, leading dimension n
  for (int c = 0; c < 2 * n; ++c) {
    const arm::BodyMatrix& d = c < n ? rigid_dq_ : rigid_dqd_;
    const int j = c < n ? c : c - n;
    double* out =
        Jdata + velocityIndex(n, 0) + static_cast<std::ptrdiff_t>(c < n ? angleIndex(n, c) : velocityIndex(n, j)) * ld;
    // The column in a local array the compiler keeps in registers at fixed N (k ascending, as before).
    double acc[kMaxPlantJoints];
    for (int r = 0; r < n; ++r) acc[r] = out[r];
    for (int k = 0; k < n; ++k) {
      const double djk = d(k, j);
      const double* minv_k = minv + static_cast<std::ptrdiff_t>(k) * n;
      for (int r = 0; r < n; ++r) acc[r] -= minv_k[r] * djk;
    }
    for (int r = 0; r < n; ++r) out[r] = acc[r];
  }
}

void ArmPlant::harvestStats() noexcept {
  void* mem = solver_->mem.get();
  long v = 0;
  SolverStats s = stats_base_;
  if (CVodeGetNumSteps(mem, &v) >= 0) s.steps += v;
  if (CVodeGetNumRhsEvals(mem, &v) >= 0) s.rhs_evals += v;
  if (CVodeGetNumJacEvals(mem, &v) >= 0) s.jac_evals += v;
  if (CVodeGetNumNonlinSolvIters(mem, &v) >= 0) s.nonlin_iters += v;
  if (CVodeGetNumNonlinSolvConvFails(mem, &v) >= 0) s.nonlin_conv_fails += v;
  if (CVodeGetNumErrTestFails(mem, &v) >= 0) s.err_test_fails += v;
  s.root_events = stats_.root_events;
  s.reinits = stats_.reinits;
  stats_ = s;
}

void ArmPlant::reinitSolver() noexcept {
  // CVodeReInit resets CVODES' counters: bank them first (docs/sources.md, Plant 3.2), unless they
  // belong to the run before the last reset().
  if (!cvodes_counters_stale_) harvestStats();
  cvodes_counters_stale_ = false;
  stats_base_ = stats_;
  stats_base_.root_events = 0;
  stats_base_.reinits = 0;
  CVodeReInit(solver_->mem.get(), t_, solver_->y.get());
  ++stats_.reinits;
  need_reinit_ = false;
}

core::RtStatus ArmPlant::step(double dt_s, const PlantCommand& command) noexcept {
  if (!solver_) {
    return core::RtStatus::fault(core::RtCode::kNotConfigured, core::kFaultNotConfigured, "plant not configured");
  }
  cmd_ = command;
  for (int k = 0; k < n_; ++k) {
    const JointParams& p = params_[static_cast<std::size_t>(k)];
    double full_scale = 1.0;
    if (p.actuator.kind == ActuatorKind::kIdealTorque) {
      full_scale = std::numeric_limits<double>::infinity();
    } else if (p.input_mode == InputMode::kValveVoltage) {
      full_scale = 1.0 / p.valve.amplifier_gain_per_v;
    } else {
      full_scale = 1.0 / (p.valve.amplifier_gain_per_v * p.torque_loop.gain_v_per_nm);
    }
    if (std::abs(cmd_.command[k] - last_cmd_.command[k]) > options_.reinit_command_jump * full_scale)
      need_reinit_ = true;
  }
  last_cmd_ = cmd_;
  if (rodas_) return stepRodas3(dt_s);
  const double t_end = t_ + dt_s;
  void* mem = solver_->mem.get();
  N_Vector y = solver_->y.get();
  core::RtStatus status;
  for (int event = 0;; ++event) {
    if (need_reinit_) reinitSolver();
    // One-shot stop time, set before every call (SUNDIALS 6.4.1 pitfall, docs/sources.md, Plant 3.2).
    CVodeSetStopTime(mem, t_end);
    double t_reached = t_;
    const int flag = CVode(mem, t_end, y, &t_reached, CV_NORMAL);
    if (flag == CV_ROOT_RETURN && t_reached < t_end - 1e-9 * dt_s && event < kMaxEventsPerPeriod) {
      // Hard-stop contact or release: the right-hand side changes form; restart the BDF history.
      ++stats_.root_events;
      t_ = t_reached;
      need_reinit_ = true;
      continue;
    }
    if (flag < 0) {
      status.raise(core::RtCode::kSolverFailure, core::kFaultSolver, "CVODES failed");
      need_reinit_ = true;
    }
    break;
  }
  t_ = t_end;
  harvestStats();
  sampleOutputs(dt_s);
  return status;
}

core::RtStatus ArmPlant::stepRodas3(double dt_s) noexcept {
  rigid_derivatives_stale_ = true;  // one exact set of rigid-body derivatives per period
  double* y = N_VGetArrayPointer(solver_->y.get());
  const core::RtStatus status = rodas_->advance(y, dt_s);
  if (!status.ok()) {
    std::snprintf(error_, sizeof(error_), "%s at t = %.6f s: %s",
                  rodas_->method() == RosenbrockMethod::kRodas4     ? "Rodas4"
                  : rodas_->method() == RosenbrockMethod::kRos34pw2 ? "ROS34PW2"
                                                                    : "Rodas3",
                  t_, status.message);
  }
  t_ += dt_s;
  const RosenbrockStats& r = rodas_->stats();
  stats_.steps = r.steps;
  stats_.rhs_evals = r.rhs_evals;
  stats_.jac_evals = r.jac_evals;
  stats_.err_test_fails = r.rejected;
  // Hard-stop contacts and releases, seen at the period boundaries (no event location: the stop
  // torque is continuous at contact, and the error control resolves the kink).
  for (int k = 0; k < n_; ++k) {
    const signed char side = stopSide(params_[static_cast<std::size_t>(k)], y[angleIndex(n_, k)]);
    if (side != stop_side_[static_cast<std::size_t>(k)]) ++stats_.root_events;
    stop_side_[static_cast<std::size_t>(k)] = side;
  }
  sampleOutputs(dt_s);
  return status;
}

void ArmPlant::sampleOutputs(double dt_s) noexcept {
  // Outputs at the period boundary, then the sensors.
  const double* yv = N_VGetArrayPointer(solver_->y.get());
  evaluateTorques(yv);
  for (int k = 0; k < n_; ++k) {
    measured_[static_cast<std::size_t>(k)] =
        sampleJointSensors(params_[static_cast<std::size_t>(k)], sensor_state_[static_cast<std::size_t>(k)], noise_,
                           yv[angleIndex(n_, k)], tau_cell_[k], dt_s);
    samplePressureSensors(params_[static_cast<std::size_t>(k)], pressure_noise_, yv[hydraulicIndex(k, kPressureA)],
                          yv[hydraulicIndex(k, kPressureB)], measured_[static_cast<std::size_t>(k)]);
  }
}

}  // namespace fullarm::plant
