// Rank 0 drives, ranks > 0 serve: see distributed.hpp. Every command starts with a broadcast
// header so all ranks enter the same collective calls in the same order.
#include "distributed.hpp"
#include "distributed_transport.hpp"

#include "../factories.hpp"
#include "../kernels.hpp"
#include "../timer.hpp"

#include "../../core/error.hpp"
#include "../solver_settings.hpp"

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <iostream>

namespace xb {

namespace {

long long g_next_id = 1;

class DistributedSolver final : public LinearSolver {
 public:
  DistributedSolver(const std::string& name, const SolverSettings& p) : LinearSolver(p.linear.tol), name_(name) {
    id_ = g_next_id++;
    if (mpi_size() > 1) {
      Header h;
      h.cmd = kCreate;
      h.id = id_;
      bcast_header(h);
      std::string n = name, text = serialize_settings(p);
      bcast_string(n);
      bcast_string(text);
    }
    std::string error;
    try {
      kernel_ = make_distributed_kernel(name, p);
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (mpi_size() > 1) error = agree_on_errors(error);  // a worker's failure is this run's error
    if (!error.empty()) throw Error(error);
  }
  ~DistributedSolver() override {
    if (mpi_size() > 1) {
      Header h;
      h.cmd = kDestroy;
      h.id = id_;
      bcast_header(h);
    }
  }
  std::string name() const override { return name_; }

  void setup(const SparseMatrix& A, SetupKind kind, const SetupContext& ctx) override {
    if (!A.isCompressed()) throw Error(name_ + ": the matrix must be in compressed CSR form");
    const Eigen::MatrixXd* nk = ctx.near_kernel;
    if (nk && nk->rows() != A.rows())
      throw Error(name_ + ": near-kernel basis has " + std::to_string(nk->rows()) + " rows, the matrix " +
                  std::to_string(A.rows()));
    // Refused on rank 0 before any rank starts: a library meeting NaN on one rank only would
    // fail there alone, inside its collective calls.
    require_finite(A.valuePtr(), A.nonZeros(), "the matrix");
    Timer t;
    const int np = mpi_size();
    const auto off = contiguous_rows(A.rows(), np, ctx.block_size);  // throws for a partial block
    A_ = &A;
    // Only values travel when the pattern is known to be the same as last time.
    const bool values_only =
        kind == SetupKind::Values && A.rows() == n_ && A.nonZeros() == nnz_ && ctx.block_size == block_size_;
    n_ = A.rows();
    nnz_ = A.nonZeros();
    block_size_ = ctx.block_size;
    if (np > 1) {
      Header h;
      h.cmd = kSetup;
      h.id = id_;
      h.values = kind == SetupKind::Values;
      h.frame = ctx.frame;
      h.substep = ctx.substep;
      h.iteration = ctx.iteration;
      h.values_only = values_only;
      h.n_global = n_;
      h.block_size = block_size_;
      h.near_kernel_cols = nk ? nk->cols() : 0;
      bcast_header(h);
      RowBlock other;
      for (int r = 1; r < np; ++r) {
        extract_block(A, nk, off[r], off[r + 1], block_size_, other, values_only);
        send_block(other, r, values_only);
      }
    }
    extract_block(A, nk, off[0], off[1], block_size_, block_, values_only);
    SetupContext local = ctx;  // as on the workers: the near-kernel rows of this block
    local.near_kernel = nk ? &block_.near_kernel : nullptr;
    collective([&] { kernel_->setup(block_, kind, local); });
    setup_time_ = t.seconds();
  }

  LinearStats solve(const Vector& b, Vector& x) override {
    if (!A_ || b.size() != n_) throw Error(name_ + ": solve() without a matching setup()");
    require_finite(b.data(), b.size(), "the right-hand side");
    Timer t;
    std::vector<double> bl, xl;
    const double tol = tolerance();
    if (mpi_size() > 1) {
      Header h;
      h.cmd = kSolve;
      h.id = id_;
      h.n_global = n_;
      h.block_size = block_size_;
      std::memcpy(&h.tol_bits, &tol, sizeof tol);
      bcast_header(h);
      scatter_vector(b.data(), n_, block_size_, bl);
    } else {
      bl.assign(b.data(), b.data() + b.size());
    }
    LinearStats st;
    collective([&] { st = kernel_->solve(bl, xl, tol); });
    x.resize(n_);
    if (mpi_size() > 1) gather_vector(xl, n_, block_size_, x.data());
    else std::copy(xl.begin(), xl.end(), x.data());
    st.solve_time = t.seconds();
    st.setup_time = setup_time_;
    setup_time_ = 0;
    // The harness's own check: ‖b − Ax‖₂ recomputed on rank 0 with the whole matrix.
    const double bnorm = norm2(b);
    Vector r;
    residual(*A_, x, b, r);
    const double rnorm = norm2(r);
    st.final_relative_residual = bnorm > 0 ? rnorm / bnorm : rnorm;
    if (!std::isfinite(rnorm) && st.status != LinearStatus::breakdown) {
      st.status = LinearStatus::breakdown;
      st.message = name_ + ": solution is not finite";
    }
    return st;
  }

  std::map<std::string, double> statistics() const override {
    auto s = kernel_->statistics();
    s["mpi_ranks"] = mpi_size();
    return s;
  }
  std::map<std::string, std::vector<double>> array_statistics() const override {
    return kernel_->array_statistics();
  }
  std::string last_setup_action() const override { return kernel_->last_setup_action(); }

 private:
  void require_finite(const double* v, long long n, const char* what) const {
    for (long long i = 0; i < n; ++i)
      if (!std::isfinite(v[i])) throw Error(name_ + ": " + what + " has a non-finite value (entry " + std::to_string(i) + ")");
  }
  // Runs this rank's part of a command; every rank then learns whether any failed, and rank 0
  // throws the first failure (a worker's with its rank), as one process would have thrown it.
  template <class F>
  void collective(F&& f) {
    std::string error;
    try {
      f();
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (mpi_size() > 1) error = agree_on_errors(error);
    if (!error.empty()) throw Error(error);
  }

  std::string name_;
  long long id_ = 0;
  std::unique_ptr<DistributedKernel> kernel_;
  const SparseMatrix* A_ = nullptr;
  long long n_ = -1, nnz_ = -1;
  int block_size_ = 1;
  RowBlock block_;
  double setup_time_ = 0;
};

bool g_workers_stopped = false;
}  // namespace

std::unique_ptr<LinearSolver> make_distributed_solver(const std::string& name, const SolverSettings& p) {
  return std::make_unique<DistributedSolver>(name, p);
}

std::unique_ptr<LinearSolver> make_hypre(const SolverSettings& p) { return make_distributed_solver("hypre", p); }
std::unique_ptr<LinearSolver> make_muelu(const SolverSettings& p) { return make_distributed_solver("muelu", p); }

namespace {
// What f threw, as text ("" if nothing): a worker's failure goes back to rank 0, it does not end the job.
template <class F>
std::string caught(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}
}  // namespace

int serve_workers() {
  std::map<long long, std::unique_ptr<DistributedKernel>> kernels;
  std::map<long long, RowBlock> blocks;
  try {
    for (;;) {
      Header h;
      // Wait for rank 0 without spinning: between solves rank 0 assembles with OpenMP on the
      // same cores, and a busy-polling MPI_Bcast would steal them.
      bcast_header(h);
      const long long id = h.id;
      switch (h.cmd) {
        case kCreate: {
          std::string name, text;
          bcast_string(name);
          bcast_string(text);
          agree_on_errors(caught([&] { kernels[id] = make_distributed_kernel(name, deserialize_settings(text)); }));
          break;
        }
        case kSetup: {
          RowBlock& blk = blocks[id];
          const int bs = static_cast<int>(h.block_size);
          blk.n_global = h.n_global;
          blk.first = contiguous_rows(h.n_global, mpi_size(), bs)[mpi_rank()];
          blk.block_size = bs;
          recv_block(blk, h.values_only, h.near_kernel_cols);
          SetupContext ctx{static_cast<int>(h.frame), static_cast<int>(h.substep), static_cast<int>(h.iteration)};
          ctx.block_size = bs;
          ctx.near_kernel = h.near_kernel_cols ? &blk.near_kernel : nullptr;  // this rank's rows only
          agree_on_errors(caught([&] { kernels.at(id)->setup(blk, h.values ? SetupKind::Values : SetupKind::Structure, ctx); }));
          break;
        }
        case kSolve: {
          std::vector<double> bl, xl;
          const int bs = static_cast<int>(h.block_size);
          scatter_vector(nullptr, h.n_global, bs, bl);
          double tol = 0;
          std::memcpy(&tol, &h.tol_bits, sizeof tol);
          // A failed solve on any rank: rank 0 throws and gathers nothing.
          if (agree_on_errors(caught([&] { kernels.at(id)->solve(bl, xl, tol); })).empty())
            gather_vector(xl, h.n_global, bs, nullptr);
          break;
        }
        case kDestroy:
          kernels.erase(id);
          blocks.erase(id);
          break;
        case kQuit:
          return 0;
        default:
          throw Error("unknown MPI command " + std::to_string(h.cmd));
      }
    }
  } catch (const std::exception& e) {
    // Only a broken protocol gets here (solver failures go back to rank 0): say why and take the job down.
    std::fprintf(stderr, "xpbd-bench (rank %d): %s\n", mpi_rank(), e.what());
    MPI_Abort(MPI_COMM_WORLD, 3);
  }
  return 3;
}

void stop_workers() {
  if (g_workers_stopped || mpi_rank() != 0 || mpi_size() == 1) return;
  g_workers_stopped = true;
  Header h;
  h.cmd = kQuit;
  bcast_header(h);
}


}  // namespace xb
