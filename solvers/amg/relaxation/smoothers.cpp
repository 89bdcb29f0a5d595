#include "smoothers.hpp"

#include "block_chebyshev.hpp"
#include "block_gs.hpp"
#include "chebyshev.hpp"
#include "gauss_seidel.hpp"

#include "../../../core/error.hpp"

namespace xb::amg {

const std::vector<std::string>& smoother_kinds() {
  static const std::vector<std::string> kinds = {"jacobi", "chebyshev", "gs", "block_gs", "block_jacobi", "block_chebyshev"};
  return kinds;
}

std::unique_ptr<Smoother> make_smoother(const SmootherOptions& opt, const SparseMatrix& A, const NodeLayout& nodes,
                                        const BlockOperator* blocks) {
  if (opt.sweeps < 1) throw Error("amg.smoother_sweeps must be >= 1");
  if (opt.degree < 1) throw Error("amg.chebyshev_degree must be >= 1");
  if (opt.kind == "jacobi" || opt.kind == "chebyshev") return std::make_unique<DiagonalSmoother>(opt, A);
  if (opt.kind == "gs") return std::make_unique<GaussSeidelSmoother>(opt, A);
  if (opt.kind == "block_gs") return std::make_unique<BlockGaussSeidelSmoother>(opt, A, nodes);
  if (opt.kind == "block_jacobi" || opt.kind == "block_chebyshev") return make_block_diagonal_smoother(opt, A, nodes, blocks);
  std::string valid;
  for (const auto& k : smoother_kinds()) valid += (valid.empty() ? "" : ", ") + k;
  throw Error("amg.smoother: unknown smoother '" + opt.kind + "' (valid: " + valid + ")");
}

}  // namespace xb::amg
