#include "global_step.hpp"

#include "../../core/error.hpp"
#include "../../solvers/timer.hpp"

namespace xb {

namespace {
// out_j = Σ_a ∇_a C_j · v(particle a) over free particles: J v for per-particle v.
void apply_J_particles(const Problem& prob, const ConstraintState& s, const Eigen::Matrix3Xd& v, Vector& out) {
  const int m = prob.num_constraints();
  out.resize(m);
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j) {
    const auto ps = prob.constraint_particles(j);
    double sum = 0;
    for (int a = 0; a < 4; ++a)
      if (ps[a] >= 0 && prob.particles.w[ps[a]] > 0) sum += s.grad[j][a].dot(v.col(ps[a]));
    out[j] = sum;
  }
}
}  // namespace

GlobalStep::GlobalStep(const Problem& prob, DualSystem& ds, const std::string& method, const Params& p,
                       const Eigen::VectorXd& alpha_tilde)
    : prob_(prob), ds_(ds), alpha_tilde_(alpha_tilde), form_(resolve_form(p.form, alpha_tilde)),
      stiffness_(p.geometric_stiffness), keep_(p.primal_residual == "keep"), newton_(p.step == "newton") {
  if (stiffness_ == "full" && form_ == "dual")
    throw Error("xpbd.geometric_stiffness=full needs the primal form (form=primal, or form=auto with every alpha~ > 0): "
                "the dual form would need the inverse of a non-diagonal top-left block");
  if (form_ == "primal")
    primal_.emplace(make_linear_solver(method, p), constraint_graph(prob), p.linear);
  else
    solver_ = make_linear_solver(method, p);
  if (stiffness_ != "none") elements_.emplace(prob);
  // M̃⁻¹ = M⁻¹ until a diagonal geometric stiffness changes it.
  const Eigen::VectorXd& w = prob.particles.w;
  minv_.resize(3, w.size());
  for (long p = 0; p < w.size(); ++p) minv_.col(p).setConstant(w[p]);
}

void GlobalStep::set_tolerance(double tol) {
  if (primal_)
    primal_->set_tolerance(tol);
  else
    solver_->set_tolerance(tol);
}

double GlobalStep::prepare(const GlobalStepInput& in) {
  Timer t;
  if (stiffness_ == "diagonal") {  // §1.4: the exact blocks' diagonals summed, then kept ≥ 0
    elements_->geometric_stiffness_diagonal(in.x, in.lambda, kd_);
    shifted_inverse_masses(prob_.particles.w, kd_, minv_);
  } else if (stiffness_ == "full" && newton_) {
    elements_->fill_energy_hessian(in.x, alpha_tilde_, in.elements ? *in.elements : ElementProjection{in.projection},
                                   nullptr, in.evaluated);
  } else if (stiffness_ == "full") {
    elements_->fill_geometric_stiffness(in.x, in.lambda, in.projection);
  }
  if (!primal_) {
    if (stiffness_ == "diagonal")
      ds_.fill(in.state, alpha_tilde_, minv_);
    else
      ds_.fill(in.state, alpha_tilde_);
  }
  return t.seconds();
}

void GlobalStep::dual_step(const GlobalStepInput& in, const Vector& dlambda, Eigen::Matrix3Xd& dx) {
  if (stiffness_ == "none" && !keep_) {  // today's step, bit for bit
    ds_.apply_minv_gradT(in.state, dlambda, dx);
    return;
  }
  ds_.apply_gradT(in.state, dlambda, dx);
  if (keep_) dx -= in.g;
  dx = dx.cwiseProduct(minv_);
}

LinearStats GlobalStep::solve(const GlobalStepInput& in, SetupKind kind, SetupContext ctx, Vector& dlambda,
                              Eigen::Matrix3Xd& dx) {
  if (!primal_) {
    const Vector* rhs = &in.b;
    if (keep_) {  // −h + J M̃⁻¹g
      apply_J_particles(prob_, in.state, in.g.cwiseProduct(minv_), rhs_);
      rhs_ += in.b;
      rhs = &rhs_;
    }
    solver_->setup(ds_.A(), kind, ctx);
    const LinearStats st = solver_->solve(*rhs, dlambda);
    if (st.status != LinearStatus::breakdown && dlambda.size() == in.b.size()) dual_step(in, dlambda, dx);
    return st;
  }
  if (stiffness_ == "none" && !keep_) {  // today's step, bit for bit
    primal_->setup(in.state.grad, alpha_tilde_, in.x, kind, ctx);
    const LinearStats st = primal_->solve(in.b, dlambda);
    if (st.status != LinearStatus::breakdown && dlambda.size() == in.b.size())
      ds_.apply_minv_gradT(in.state, dlambda, dx);
    return st;
  }
  setup_primal(in, kind, ctx);
  const std::vector<int>& free = primal_->system().free_particles();
  const long nb = static_cast<long>(free.size());
  to_dofs(in.g, g_dof_);
  const LinearStats st = primal_->solve(in.b, dlambda, keep_ ? &g_dof_ : nullptr, &dx_dof_);
  dx.setZero(3, prob_.particles.size());
  if (dx_dof_.size() == 3 * nb) {
    for (int d : held_dofs_) dx_dof_[d] = 0;  // exactly: Jᵀα̃⁻¹b (≈ 0 under newton) is not zeroed
    for (long i = 0; i < nb; ++i) dx.col(free[i]) = dx_dof_.segment<3>(3 * i);
  }
  return st;
}

void GlobalStep::setup(const GlobalStepInput& in, SetupKind kind, SetupContext ctx) {
  if (!primal_ || !newton_ || stiffness_ != "full")
    throw Error("GlobalStep::setup: only step = newton's primal form is set up without a solve");
  setup_primal(in, kind, ctx);
}

void GlobalStep::setup_primal(const GlobalStepInput& in, SetupKind kind, SetupContext ctx) {
  const std::vector<int>& free = primal_->system().free_particles();
  const long nb = static_cast<long>(free.size());
  top_ = TopLeftBlock{};
  const Gradients& grad = in.state.grad;
  if (stiffness_ == "diagonal") {
    minv_dof_.resize(3 * nb);
    for (long i = 0; i < nb; ++i) minv_dof_.segment<3>(3 * i) = minv_.col(free[i]);
    top_.inv_mass = &minv_dof_;
    top_.fill = [this, &grad](PrimalSystem& sys) { sys.fill_with_diagonal(grad, alpha_tilde_, kd_); };
  } else if (stiffness_ == "full" && newton_) {
    newton_top(in);
  } else if (stiffness_ == "full") {
    top_.fill = [this, &grad](PrimalSystem& sys) { sys.fill_with_blocks(grad, alpha_tilde_, elements_->blocks()); };
  }
  primal_->setup(in.state.grad, alpha_tilde_, in.x, kind, ctx, top_);
}

void GlobalStep::newton_top(const GlobalStepInput& in) {
  const std::vector<int>& free = primal_->system().free_particles();
  held_dofs_.clear();
  if (in.held && !in.held->empty()) {  // y of particle free[i] is K's row 3i + 1
    std::vector<int> block(prob_.particles.size(), -1);
    for (size_t i = 0; i < free.size(); ++i) block[free[i]] = static_cast<int>(i);
    for (int p : *in.held)
      if (block[p] >= 0) held_dofs_.push_back(3 * block[p] + 1);
  }
  top_ = TopLeftBlock{};
  top_.fill = [this](PrimalSystem& sys) {
    sys.fill_energy_hessian(elements_->blocks());
    sys.fix_dofs(held_dofs_);
  };
}

void GlobalStep::to_dofs(const Eigen::Matrix3Xd& v, Vector& out) const {
  const std::vector<int>& free = primal_->system().free_particles();
  out.resize(3 * static_cast<long>(free.size()));
  for (size_t i = 0; i < free.size(); ++i) out.segment<3>(3 * static_cast<long>(i)) = v.col(free[i]);
  for (int d : held_dofs_) out[d] = 0;
}

double GlobalStep::curvature(const Eigen::Matrix3Xd& s) {
  if (!primal_ || !newton_) throw Error("GlobalStep::curvature: step = newton in the primal form only");
  to_dofs(s, work_dofs_);
  return work_dofs_.dot(primal_->system().K() * work_dofs_);
}

const SparseMatrix& GlobalStep::fill_newton_system(const GlobalStepInput& in, Vector& g_dof) {
  if (!primal_ || !newton_ || stiffness_ != "full")
    throw Error("GlobalStep::fill_newton_system: step = newton with the full geometric stiffness only");
  prepare(in);
  newton_top(in);
  primal_->fill(in.state.grad, alpha_tilde_, top_);
  to_dofs(in.g, g_dof);
  return primal_->system().K();
}

}  // namespace xb
