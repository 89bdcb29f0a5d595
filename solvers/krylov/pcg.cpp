#include "pcg.hpp"

#include "../kernels.hpp"
#include "../timer.hpp"

#include <cmath>

namespace xb {

LinearStats pcg(const SparseMatrix& A, const Vector& b, Vector& x, const Preconditioner& precond, double tol,
                int max_iterations, const RelativeResidual& rel, bool natural_norm) {
  LinearStats st;
  Timer clock;
  const long n = b.size();
  x = Vector::Zero(n);
  Vector r = b, z(n), p(n), Ap(n);
  const double bnorm = norm2(b);
  auto relative = [&](const Vector& res) { return rel ? rel(res) : norm2(res) / bnorm; };
  st.residual_history.push_back(bnorm);
  st.residual_time.push_back(clock.seconds());
  if (!std::isfinite(bnorm)) {
    st.status = LinearStatus::breakdown;
    st.message = "right-hand side is not finite";
    return st;
  }
  if (bnorm == 0) {
    st.solve_time = clock.seconds();
    return st;
  }
  auto apply_precond = [&](const Vector& in, Vector& out) {
    if (precond)
      precond(in, out);
    else
      out = in;
  };
  apply_precond(r, z);
  p = z;
  double rz = dot(r, z);
  const double rz0 = rz;
  st.status = LinearStatus::max_iterations;
  for (int k = 0; k < max_iterations; ++k) {
    const double pAp = spmv_dot(A, p, Ap);
    if (!(pAp > 0) || !std::isfinite(pAp) || !(rz > 0)) {
      st.status = LinearStatus::breakdown;
      st.message = !(pAp > 0) ? "p'Ap <= 0: matrix not positive definite" : "r'z <= 0: preconditioner not positive definite";
      break;
    }
    const double alpha = rz / pAp;
    const double rr = cg_update(alpha, p, Ap, x, r);
    st.iterations = k + 1;
    const double rnorm = rel ? rel(r) * bnorm : std::sqrt(rr);
    st.residual_history.push_back(rnorm);
    st.residual_time.push_back(clock.seconds());
    if (!std::isfinite(rnorm)) {
      st.status = LinearStatus::breakdown;
      st.message = "residual is not finite";
      break;
    }
    if (!natural_norm && rnorm <= tol * bnorm) {
      st.status = LinearStatus::converged;
      break;
    }
    apply_precond(r, z);
    const double rz_new = dot(r, z);
    if (natural_norm && rz_new >= 0 && std::sqrt(rz_new) <= tol * std::sqrt(rz0)) {
      st.status = LinearStatus::converged;
      break;
    }
    const double beta = rz_new / rz;
    rz = rz_new;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
  }
  st.solve_time = clock.seconds();
  Vector rtrue;
  residual(A, x, b, rtrue);
  st.final_relative_residual = relative(rtrue);
  return st;
}

}  // namespace xb
