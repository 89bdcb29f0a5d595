#include "steihaug.hpp"

#include "../kernels.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <cmath>

namespace xb {

const char* to_string(SteihaugExit e) {
  switch (e) {
    case SteihaugExit::interior: return "interior";
    case SteihaugExit::boundary: return "boundary";
    case SteihaugExit::negative_curvature: return "negative_curvature";
    case SteihaugExit::max_iterations: return "max_iterations";
  }
  return "?";
}

double step_to_boundary(double pp, double pd, double dd, double radius) {
  if (!(dd > 0)) return 0;
  const double room = std::max(0.0, radius * radius - pp);
  // The positive root of dd·τ² + 2pd·τ − room = 0, in the form without cancellation.
  const double disc = std::sqrt(pd * pd + dd * room);
  return pd <= 0 ? (disc - pd) / dd : room / (disc + pd);
}

SteihaugResult steihaug_toint(const SparseMatrix& K, const Vector& g, double radius, const Preconditioner& precond,
                              double tol, int max_iterations) {
  if (K.rows() != K.cols() || K.rows() != g.size())
    throw Error("Steihaug-Toint CG: K is " + std::to_string(K.rows()) + " x " + std::to_string(K.cols()) +
                ", g has " + std::to_string(g.size()) + " entries");
  if (!(radius > 0)) throw Error("Steihaug-Toint CG: the trust-region radius must be > 0");
  const long n = g.size();
  SteihaugResult out;
  out.p = Vector::Zero(n);
  Vector r = -g, z(n), d(n), Kd(n);
  auto apply = [&](const Vector& in, Vector& o) {
    if (precond)
      precond(in, o);
    else
      o = in;
  };
  const double gnorm = norm2(g);
  apply(r, z);
  d = z;
  double rz = dot(r, z);
  // ‖p‖²_P, pᵀPd, dᵀPd by CG's recurrences (p ∈ span{d₀…d_{k−1}} and rₖ ⟂ it, so pᵀPz = pᵀr = 0).
  double pp = 0, pd = 0, dd = rz;
  auto finish = [&](SteihaugExit e) {
    out.exit = e;
    out.norm = std::sqrt(std::max(0.0, pp));
    out.model = dot(g, out.p) + 0.5 * spmv_dot(K, out.p, out.Kp);
    return out;
  };
  if (gnorm == 0 || !(rz > 0)) return finish(SteihaugExit::interior);
  for (int k = 0; k < max_iterations; ++k) {
    const double dKd = spmv_dot(K, d, Kd);
    ++out.iterations;
    if (!(dKd > 0)) {  // negative (or zero) curvature: to the boundary along d
      const double tau = step_to_boundary(pp, pd, dd, radius);
      axpy(tau, d, out.p);
      pp += 2 * tau * pd + tau * tau * dd;
      out.curvature = dKd / dd;
      return finish(SteihaugExit::negative_curvature);
    }
    const double alpha = rz / dKd;
    const double next = pp + 2 * alpha * pd + alpha * alpha * dd;
    if (next >= radius * radius) {
      const double tau = step_to_boundary(pp, pd, dd, radius);
      axpy(tau, d, out.p);
      pp = radius * radius;
      return finish(SteihaugExit::boundary);
    }
    const double rr = cg_update(alpha, d, Kd, out.p, r);
    pp = next;
    if (std::sqrt(rr) <= tol * gnorm) return finish(SteihaugExit::interior);
    apply(r, z);
    const double rz_new = dot(r, z);
    if (!(rz_new > 0)) return finish(SteihaugExit::interior);  // r = 0 in P's norm: solved
    const double beta = rz_new / rz;
    pd = beta * (pd + alpha * dd);
    dd = rz_new + beta * beta * dd;
    rz = rz_new;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) d[i] = z[i] + beta * d[i];
  }
  return finish(SteihaugExit::max_iterations);
}

}  // namespace xb
