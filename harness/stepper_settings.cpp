#include "stepper_settings.hpp"

#include "../problems/primal_system.hpp"

namespace xb {

const std::vector<std::string>& hessian_projection_choices() {
  static const std::vector<std::string> v = {"clamp", "abs", "adaptive", "on_demand", "progressive", "rho_switch"};
  return v;
}

const SettingTable<StepperSettings>& stepper_settings() {
  using S = StepperSettings;
  constexpr double inf = 1e300;
  static const SettingTable<S> table = {
      setting("max_iterations", "outer iterations per substep", &S::max_iterations, 1, 1e9).applies({on("")}),
      setting("rtol", "outer stop: dual residual relative to iteration 0", &S::rtol, 0, inf).applies({on("")}),
      setting("atol", "outer stop: absolute dual residual", &S::atol, 0, inf).applies({on("")}),
      setting("omega", "global step size x += omega M^-1 grad C^T dlambda", &S::omega, 1e-300, 2).applies({on("global").where("step=fixed")}),
      setting("residual_metric", "dual residual of the stop test: true (|C(x_k) + alpha~ lambda_k|) | authors (|C(x~) + alpha~ lambda_k| local, |C(x_k-1) + alpha~ lambda_k| global)", &S::residual_metric, {"true", "authors"}).applies({on("").where("step!=newton")}),
      setting("step", "global step: fixed (x += omega M^-1 grad C^T dlambda) | line_search (lambda += dlambda, then x += t dx with t = 1, 1/2, ... the first that lowers |C(x) + alpha~ lambda|) | newton (Newton on E(x): lambda = -C/alpha~ every iterate, Armijo backtracking on E, rtol/atol read |grad E|)", &S::step, {"fixed", "line_search", "newton"}).applies({on("global")}),
      setting("threads", "OpenMP threads (0 = default)", &S::threads, 0, 4096)
          .record_only("a run's results are the same at any thread count (docs/determinism.md)"),
      setting("form", "linear step of global methods: dual (A dlambda = b) | primal (K dx = J^T alpha~^-1 b, every alpha~ > 0) | auto (primal when every alpha~ > 0)", &S::form, form_choices()).applies({on("global").also_solve()}),
      setting("xpbd.geometric_stiffness", "top-left block of the step: none (M, XPBD's) | diagonal (M + the per-particle non-negative diagonal of -sum lambda_j hess C_j) | full (M - sum lambda_j hess C_j, each part PSD-projected; primal form only)", &S::geometric_stiffness, {"none", "diagonal", "full"}).applies({on("global")}),
      setting("xpbd.primal_residual", "primal residual g = M(x - x~) - grad C^T lambda in the step's right-hand side: zero (XPBD's) | keep", &S::primal_residual, {"zero", "keep"}).applies({on("global")}),
      setting("xpbd.hessian_projection", "PSD projection of each element's geometric stiffness (full): clamp (negative eigenvalues to 0) | abs | and under step = newton: adaptive (clamp until |grad E| < xpbd.exact_hessian_below of its first value, then exact) | on_demand (exact, clamped for a step that fails) | progressive (exact but the elements below -tau of their own stiffness clamped) | rho_switch (clamp, abs after a step the quadratic model predicted poorly: Chen et al.'s rho-driven switch, not a trust region)", &S::hessian_projection, hessian_projection_choices())
          .applies({on("global").where("xpbd.geometric_stiffness=full").where("xpbd.globalization=line_search")}),
      setting("xpbd.line_search", "step = newton's line search on E: robust_armijo (Armijo, and below E's rounding the trapezoid rule on the gradients) | armijo", &S::line_search, {"robust_armijo", "armijo"}).applies({on("global").where("step=newton").where("xpbd.globalization=line_search")}),
      setting("xpbd.globalization", "step = newton's globalisation: line_search (the projected step, then xpbd.line_search) | trust_region (the exact Hessian's quadratic model in a trust region, radius by the ratio of actual to predicted decrease; its subproblem: xpbd.trust_region_subproblem)", &S::globalization, {"line_search", "trust_region"}).applies({on("global").where("step=newton")}),
      setting("xpbd.trust_region_subproblem", "xpbd.globalization = trust_region's subproblem solver: steihaug (Steihaug-Toint CG on the exact K, preconditioned by the run's linear method on the clamped K) | more_sorensen (K + sigma K_c factorised by CHOLMOD, sigma by the secular equation; needs solver cholmod)", &S::trust_region_subproblem, {"steihaug", "more_sorensen"})
          .applies({on("cholmod").where("step=newton").where("xpbd.globalization=trust_region")}),
      setting("xpbd.exact_hessian_below", "adaptive projection: relative |grad E| below which the exact Hessian is tried", &S::exact_hessian_below, 0, 1)
          .applies({on("global").where("step=newton").where("xpbd.hessian_projection=adaptive").where("xpbd.globalization=line_search")}),
      setting("reference.method", "--reference solution: newton (Newton on E with cholmod to |grad E| <= 1e-10 relative, every alpha~ > 0) | xpbd (XPBD's fixed point by cholmod) | auto (newton where every alpha~ > 0, else xpbd)", &S::reference_method, {"auto", "newton", "xpbd"}).applies({on("").with_reference()}),
      setting("reference.linear", "linear method of the newton reference's solves: cholmod (exact) | mgpbd | jacobi-pcg (iterative, Eisenstat-Walker down to 1e-12: where the factor does not fit; the stop test on |grad E| is the same)", &S::reference_linear, {"cholmod", "mgpbd", "jacobi-pcg"}).applies({on("").with_reference().where("reference.method!=xpbd")}),
      setting("reference.globalization", "the newton reference's globalisation: line_search (progressive projection, robust Armijo) | trust_region (the exact Hessian in a trust region: reference.trust_region_subproblem)", &S::reference_globalization, {"line_search", "trust_region"})
          .applies({on("").with_reference().where("reference.method!=xpbd")}),
      setting("reference.trust_region_subproblem", "reference.globalization = trust_region's subproblem solver: steihaug (Steihaug-Toint CG preconditioned by reference.linear on the clamped K: CHOLMOD's factor by default) | more_sorensen (K + sigma K_c by CHOLMOD; needs reference.linear = cholmod)", &S::reference_trust_region_subproblem, {"steihaug", "more_sorensen"})
          .applies({on("").with_reference().where("reference.method!=xpbd").where("reference.globalization=trust_region").where("reference.linear=cholmod")}),
  };
  return table;
}

}  // namespace xb
