// xb_newton_measure: the measurements behind docs/newton.md's account of the collapsed squash (a
// tool beside the tests, not a test). For the first substep of a scene it runs the stepper's Newton
// loop (line search or trust region, by the parameters) from x̃ or from a saved state's positions,
// prints every iterate (‖∇E‖, E, the step's size, the inverted tets and their smallest σ₂ + σ₃, the
// trust region's radius, ρ, σ and element-mode curvature), and at the end the exact Hessian's
// factorisation by CHOLMOD (positive definite or not) and, with --bracket, λ_min(M⁻¹K) bracketed by
// shifted factorisations.
//   xb_newton_measure --scene squash --set mesh=bunny:270k [--set key=value]... [--solver cholmod]
//                     [--start STATE.h5] [--save-end STATE.h5] [--compare STATE.h5] [--bracket]
// The profile is `newton` (its keys under --set). --start: a state file (run --save-state) whose
// positions start the minimisation of the same E (the scene's first substep, x̃ from its start).
// --save-end: the last iterate as a state file (frame 1, v = (x − x₀)/h); --compare: the distance
// ‖x − x_STATE‖_M/‖x_STATE − x̃‖_M of the last iterate from a state's positions, and E at both.
#include "harness/cli/run_setup.hpp"
#include "harness/io/state_io.hpp"
#include "harness/sim/forcing.hpp"
#include "harness/sim/newton.hpp"
#include "harness/sim/newton_loop.hpp"
#include "harness/sim/reference.hpp"
#include "harness/sim/residual_energy.hpp"
#include "problems/primal_system.hpp"
#include "problems/scene.hpp"
#include "solvers/kernels.hpp"
#include "solvers/timer.hpp"

#include "core/error.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

using namespace xb;

namespace {

struct Options {
  std::string scene = "squash", solver = "cholmod", start, save_end, compare;
  std::vector<std::string> sets;
  bool bracket = false;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Error("xb_newton_measure: " + a + " needs a value");
      return argv[++i];
    };
    if (a == "--scene") o.scene = value();
    else if (a == "--set") o.sets.push_back(value());
    else if (a == "--solver") o.solver = value();
    else if (a == "--start") o.start = value();
    else if (a == "--save-end") o.save_end = value();
    else if (a == "--compare") o.compare = value();
    else if (a == "--bracket") o.bracket = true;
    else throw Error("xb_newton_measure: unknown argument '" + a + "'");
  }
  return o;
}

// K + σM factorised by CHOLMOD: positive definite or not.
bool positive_definite(LinearSolver& chol, const SparseMatrix& K, const Vector& mass, double sigma, bool first) {
  SparseMatrix S = K;
  for (int i = 0; i < S.rows(); ++i) S.coeffRef(i, i) += sigma * mass[i];
  chol.setup(S, first ? SetupKind::Structure : SetupKind::Values, SetupContext{});
  return chol.preconditioner() != nullptr;
}

// The exact K = M + Σ H_j at x: positive definite or not, and with `bracket` λ_min(M⁻¹K) between two
// shifts (bisection by factorisations, to 2%).
void hessian_inertia(const Problem& prob, const Params& p, const Eigen::Matrix3Xd& x, const Eigen::VectorXd& at,
                     bool bracket) {
  ElementHessians eh(prob);
  ConstraintState st;
  eh.evaluate(x, st);
  eh.fill_energy_hessian(x, at, ElementProjection{Projection::none, 0}, nullptr, true);
  PrimalSystem ps(constraint_graph(prob));
  ps.fill_energy_hessian(eh.blocks());
  Vector mass(ps.rows());
  for (size_t i = 0; i < ps.free_particles().size(); ++i)
    mass.segment<3>(3 * i).setConstant(1.0 / prob.particles.w[ps.free_particles()[i]]);
  SolverSettings s = p;
  s.cholmod.refactor = "always";
  auto chol = make_linear_solver("cholmod", s);
  Timer t;
  const bool pd = positive_definite(*chol, ps.K(), mass, 0, true);
  double twist = INFINITY;
  const int inverted = eh.inverted_tets(twist);
  std::printf("end: exact K (%d rows) %s by CHOLMOD (%.1f s); %d of %d elements indefinite; %d tets inverted, "
              "smallest sigma2+sigma3 %.3g\n",
              ps.rows(), pd ? "POSITIVE DEFINITE" : "NOT positive definite", t.seconds(), eh.indefinite_elements(),
              prob.num_constraints(), inverted, twist);
  if (!bracket) return;
  // λ_min(M⁻¹K) ∈ (lo, hi]: K − σM is positive definite exactly for σ < λ_min.
  auto pd_below = [&](double sigma) { return positive_definite(*chol, ps.K(), mass, -sigma, false); };
  double lo = 0, hi = 0;
  if (pd) {
    hi = 1;
    while (pd_below(hi)) lo = hi, hi *= 4;
  } else {
    lo = -1;
    while (!pd_below(lo)) hi = lo, lo *= 4;
  }
  for (int k = 0; k < 40 && hi - lo > 0.02 * std::max(std::abs(lo), std::abs(hi)); ++k) {
    const double mid = 0.5 * (lo + hi);
    (pd_below(mid) ? lo : hi) = mid;
  }
  std::printf("end: lambda_min(M^-1 K) in [%.4g, %.4g] (h^2 units: K = h^2 hess E)\n", lo, hi);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options o = parse(argc, argv);
    const Params p = resolve_params(o.scene, o.sets, "newton");
    const Problem prob = build_problem(p);
    const double h = p.dt / p.substeps;
    const Eigen::VectorXd at = scaled_compliance(prob, h);
    Eigen::Matrix3Xd v = prob.particles.v, x_pred = prob.particles.x;
    for (int i = 0; i < prob.particles.size(); ++i)
      if (prob.particles.w[i] > 0) x_pred.col(i) += h * (v.col(i) + h * prob.gravity);
    Eigen::Matrix3Xd start;
    if (!o.start.empty()) {
      start = read_state(o.start).x;
      if (start.cols() != x_pred.cols()) throw Error("xb_newton_measure: --start has another particle count");
    }
    DualSystem ds(prob);
    GlobalStep step(prob, ds, o.solver, p, at);
    NewtonLoop loop(prob, ds, step, at, h, NewtonSettings::from(p));
    ForcingRule forcing(p.linear);
    ConstraintState s0;
    evaluate_constraints(prob, x_pred, s0, newton_rest_epsilon);
    const double g_pred = energy_gradient_norm(prob, ds, s0, x_pred, x_pred, at, h);
    std::printf("%s: %d particles, %d constraints; |grad E(x~)| = %.6g\n", o.scene.c_str(), prob.particles.size(),
                prob.num_constraints(), g_pred);
    std::printf("it  |gradE|/|gradE(x~)|  E  |dx|_M/|x-x~|_M  inverted  min(s2+s3)  radius  rho  sigma  curvature  "
                "rejected  linear_its  s\n");
    Eigen::Matrix3Xd previous;
    double last_step = 0;
    Timer clock;
    NewtonHooks hooks;
    hooks.tolerance = [&](int it, double gradient) { return forcing.next(it, gradient); };
    hooks.on_iterate = [&](const NewtonIterate& it) {
      const double scale = mass_norm_distance(prob, it.x, x_pred);
      last_step = it.iteration > 0 ? mass_norm_distance(prob, it.x, previous) / scale : 0;
      previous = it.x;
      const StepRecord& r = it.last;
      std::printf("%d %.3e %.10e %.3e %d %.3g %.3g %.3g %.3g %.3g %d %d %.1f\n", it.iteration, it.gradient / g_pred,
                  it.energy, last_step, it.inverted, it.twist_sum, r.radius, r.ratio, r.shift, r.curvature, r.rejected,
                  r.linear.iterations, clock.seconds());
      std::fflush(stdout);
    };
    Eigen::Matrix3Xd x;
    const NewtonOutcome out = loop.minimise(x, x_pred, hooks, o.start.empty() ? nullptr : &start);
    std::printf("end: %s after %d iterations, %.1f s; |grad E|/|grad E(x~)| %.3e (floor %.3e); last step %.3e of "
                "|x - x~|_M = %.6g\n",
                stop_reason_name(out.reason).c_str(), out.iterations, clock.seconds(), out.gradient / g_pred,
                out.floor / g_pred, last_step, mass_norm_distance(prob, x, x_pred));
    if (!o.compare.empty()) {
      const Eigen::Matrix3Xd y = read_state(o.compare).x;
      ConstraintState sy, sx;
      evaluate_constraints(prob, y, sy, newton_rest_epsilon);
      evaluate_constraints(prob, x, sx, newton_rest_epsilon);
      std::printf("compare: |x - x_cmp|_M/|x_cmp - x~|_M = %.4g; E(x) = %.10e, E(x_cmp) = %.10e, |grad E(x_cmp)|/|grad E(x~)| "
                  "= %.3e\n",
                  mass_norm_distance(prob, x, y) / mass_norm_distance(prob, y, x_pred),
                  incremental_energy(prob, sx, x, x_pred, h), incremental_energy(prob, sy, y, x_pred, h),
                  energy_gradient_norm(prob, ds, sy, y, x_pred, at, h) / g_pred);
      if (!o.start.empty())
        std::printf("compare: the start's |x_start - x_cmp|_M/|x_cmp - x~|_M = %.4g\n",
                    mass_norm_distance(prob, start, y) / mass_norm_distance(prob, y, x_pred));
    }
    hessian_inertia(prob, p, x, at, o.bracket);
    if (!o.save_end.empty()) write_state(o.save_end, SimState{1, x, (x - prob.particles.x) / h}, p);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
}
