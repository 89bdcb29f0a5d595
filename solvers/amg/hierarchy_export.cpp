#include "hierarchy_export.hpp"

#include "../../core/error.hpp"

namespace xb::amg {

namespace {
SmootherExport export_smoother(const Smoother& s) {
  SmootherExport e;
  e.kind = s.name();
  const DiagonalRelaxation<double>* r = s.relaxation();
  if (!r) return e;  // Gauss–Seidel: no polynomial form
  e.polynomial = true;
  e.sweeps = r->sweeps;
  e.degree = r->chebyshev ? r->degree : 1;
  e.lambda_max = r->lambda;
  e.lower = r->chebyshev ? r->lambda / 30.0 : r->lambda;
  e.upper = r->chebyshev ? 1.1 * r->lambda : r->lambda;
  e.steps = r->steps();
  if (r->node_start.empty()) {
    e.inv_diag = r->inv_diag;
    return e;
  }
  e.node_start = r->node_start;
  // The blocks as stored, in node order (offset[I] is where node I's starts).
  const int nn = static_cast<int>(r->node_start.size()) - 1;
  for (int I = 0; I < nn; ++I) {
    const int nb = r->node_start[I + 1] - r->node_start[I];
    const double* M = r->block_inv.data() + r->offset[I];
    e.block_inv.insert(e.block_inv.end(), M, M + static_cast<long>(nb) * nb);
  }
  return e;
}
}  // namespace

HierarchyExport export_hierarchy(const Hierarchy& h) {
  if (h.empty()) throw Error("mgpbd: export of a hierarchy that is not set up");
  HierarchyExport out;
  out.precision = h.options().precision;
  out.coarse_solver = h.options().coarse_solver;
  out.block_size = h.level(0).nodes.scalar() ? 1 : h.level(0).nodes.node_start[1];
  const int nl = h.num_levels();
  out.levels.resize(nl);
  for (int l = 0; l < nl; ++l) {
    const Level& L = h.level(l);
    LevelExport& e = out.levels[l];
    e.A = h.matrix(l);
    e.A.makeCompressed();
    if (l + 1 < nl) {
      e.P = L.T.P;
      e.R = L.T.R;
      e.P.makeCompressed();
      e.R.makeCompressed();
    }
    if (L.smoother && (l + 1 < nl || out.coarse_solver == "smoother")) e.smoother = export_smoother(*L.smoother);
  }
  return out;
}

}  // namespace xb::amg
