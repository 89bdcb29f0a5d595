#include "block_gs.hpp"

#include "../nodal.hpp"
#include "../../kernels.hpp"

#include <algorithm>
#include <vector>

namespace xb::amg {

Coloring node_coloring(const SparseMatrix& A, const NodeLayout& nodes) {
  return nodes.scalar() ? greedy_coloring(A) : greedy_coloring(node_matrix(A, nodes));
}

void block_gs_sweep(const SparseMatrix& A, const BlockDiagonal& D, const Coloring& coloring, const Vector& b,
                    Vector& x, bool forward) {
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
  const double* av = A.valuePtr();
  const int* order = coloring.order.data();
  const long rows_per_node = std::max(1, D.rows() / std::max(1, D.num_nodes()));
  for (int cc = 0; cc < coloring.num_colors; ++cc) {
    const int c = forward ? cc : coloring.num_colors - 1 - cc;
    const int lo = coloring.color_start[c], hi = coloring.color_start[c + 1];
    // Nodes of one colour are independent: the order inside a colour does not matter.
#pragma omp parallel if ((hi - lo) * rows_per_node > kMinParallelRows)
    {
      std::vector<double> res;  // the node's residual b_I − (A x)_I
#pragma omp for schedule(static)
      for (int t = lo; t < hi; ++t) {
        const int I = order[t];
        const int s = D.node_begin(I), bs = D.node_end(I) - s;
        res.resize(bs);
        for (int r = 0; r < bs; ++r) {
          double acc = b[s + r];
          for (int k = ao[s + r]; k < ao[s + r + 1]; ++k) acc -= av[k] * x[ac[k]];
          res[r] = acc;
        }
        const double* Dinv = D.inverse_block(I);
        for (int r = 0; r < bs; ++r) {
          double acc = 0;
          for (int q = 0; q < bs; ++q) acc += Dinv[r * bs + q] * res[q];
          x[s + r] += acc;
        }
      }
    }
  }
}

BlockGaussSeidelSmoother::BlockGaussSeidelSmoother(const SmootherOptions& opt, const SparseMatrix& A,
                                                   const NodeLayout& nodes)
    : opt_(opt), nodes_(nodes), coloring_(node_coloring(A, nodes)) {
  D_.build(A, nodes_);
}

void BlockGaussSeidelSmoother::presmooth(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) {
  if (x_zero) x.setZero(b.size());
  for (int s = 0; s < opt_.sweeps; ++s) block_gs_sweep(A, D_, coloring_, b, x, true);
}

void BlockGaussSeidelSmoother::postsmooth(const SparseMatrix& A, const Vector& b, Vector& x) {
  for (int s = 0; s < opt_.sweeps; ++s) block_gs_sweep(A, D_, coloring_, b, x, false);
}

}  // namespace xb::amg
