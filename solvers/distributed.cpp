// Rank 0 drives, ranks > 0 serve: see distributed.hpp. Every command starts with a broadcast
// header so all ranks enter the same collective calls in the same order.
#include "distributed.hpp"

#include "factories.hpp"
#include "kernels.hpp"
#include "timer.hpp"

#include "../problems/error.hpp"
#include "../problems/params.hpp"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <iostream>
#include <numeric>
#include <sstream>
#include <thread>

namespace xb {

namespace {
// main() initialises MPI; library users without it (the unit tests) get it on first use,
// finalised at exit.
void ensure_mpi() {
  int init = 0;
  MPI_Initialized(&init);
  if (init) return;
  MPI_Init(nullptr, nullptr);
  std::atexit([] {
    int fin = 0;
    MPI_Finalized(&fin);
    if (fin) return;
    finalize_external_libraries();
    MPI_Finalize();
  });
}
}  // namespace

int mpi_rank() {
  ensure_mpi();
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int mpi_size() {
  ensure_mpi();
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

std::vector<long long> contiguous_rows(long long n, int nranks) {
  std::vector<long long> off(nranks + 1);
  for (int r = 0; r <= nranks; ++r) off[r] = n * r / nranks;
  return off;
}

void DistributedKernel::record_setup(const std::string& action, bool full) {
  action_ = action;
  ++(full ? full_setups_ : reused_setups_);
}

void DistributedKernel::record_levels(std::vector<double> rows, std::vector<double> nnz) {
  level_rows_ = std::move(rows);
  level_nnz_ = std::move(nnz);
}

std::map<std::string, double> DistributedKernel::statistics() const {
  const auto sum = [](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); };
  const bool any = !level_rows_.empty() && level_rows_[0] > 0 && level_nnz_[0] > 0;
  return {{"levels", static_cast<double>(level_rows_.size())},
          {"operator_complexity", any ? sum(level_nnz_) / level_nnz_[0] : 0},
          {"grid_complexity", any ? sum(level_rows_) / level_rows_[0] : 0},
          {"setup_full", static_cast<double>(full_setups_)},
          {"setup_reused", static_cast<double>(reused_setups_)}};
}

std::map<std::string, std::vector<double>> DistributedKernel::array_statistics() const {
  return {{"level_rows", level_rows_}, {"level_nnz", level_nnz_}};
}

bool method_is_distributed(const std::string& name) { return name == "hypre" || name == "muelu"; }

namespace {

enum Cmd : long long { kCreate = 1, kSetup, kSolve, kDestroy, kQuit };
// Header: {cmd, id, kind, frame, substep, iteration, values_only, n_global}
using Header = long long[8];

std::unique_ptr<DistributedKernel> make_kernel(const std::string& name, const Params& p) {
#ifdef XB_WITH_HYPRE
  if (name == "hypre") return make_hypre_kernel(p);
#endif
#ifdef XB_WITH_MUELU
  if (name == "muelu") return make_muelu_kernel(p);
#endif
  (void)p;
  throw Error("solver '" + name + "' has no distributed kernel in this build");
}

// Every command header goes through this non-blocking broadcast (blocking and non-blocking
// collectives must not be mixed). Waiting ranks sleep between tests instead of spinning.
void bcast_header(Header& h) {
  MPI_Request req;
  MPI_Ibcast(h, 8, MPI_LONG_LONG, 0, MPI_COMM_WORLD, &req);
  for (int done = 0;;) {
    MPI_Test(&req, &done, MPI_STATUS_IGNORE);
    if (done) break;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

void bcast_string(std::string& s) {
  long long len = static_cast<long long>(s.size());
  MPI_Bcast(&len, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
  s.resize(len);
  if (len) MPI_Bcast(s.data(), static_cast<int>(len), MPI_CHAR, 0, MPI_COMM_WORLD);
}

// Params as "key=value" lines through the one field table (so workers see exactly rank 0's).
std::string serialize(const Params& p) {
  std::string s;
  for (const auto& f : param_fields()) s += f.key + "=" + param_to_string(p, f) + "\n";
  return s;
}

Params deserialize(const std::string& text) {
  Params p;
  std::istringstream is(text);
  for (std::string line; std::getline(is, line);) {
    const auto eq = line.find('=');
    if (eq != std::string::npos) set_param(p, line.substr(0, eq), line.substr(eq + 1), "mpi");
  }
  return p;
}

// Rank r's rows of A (global column indices).
void extract_block(const SparseMatrix& A, long long first, long long last, RowBlock& blk, bool values_only) {
  const int* op = A.outerIndexPtr();
  const int* ii = A.innerIndexPtr();
  const double* vv = A.valuePtr();
  const long long b0 = op[first], b1 = op[last];
  blk.n_global = A.rows();
  blk.first = first;
  blk.vals.assign(vv + b0, vv + b1);
  if (values_only) return;
  blk.rowptr.resize(last - first + 1);
  for (long long i = first; i <= last; ++i) blk.rowptr[i - first] = static_cast<int>(op[i] - b0);
  blk.cols.assign(ii + b0, ii + b1);
}

template <class T>
MPI_Datatype mpi_type();
template <>
MPI_Datatype mpi_type<int>() { return MPI_INT; }
template <>
MPI_Datatype mpi_type<long long>() { return MPI_LONG_LONG; }
template <>
MPI_Datatype mpi_type<double>() { return MPI_DOUBLE; }

template <class T>
void send_vec(const std::vector<T>& v, int to) {
  long long n = static_cast<long long>(v.size());
  MPI_Send(&n, 1, MPI_LONG_LONG, to, 0, MPI_COMM_WORLD);
  if (n) MPI_Send(v.data(), static_cast<int>(n), mpi_type<T>(), to, 0, MPI_COMM_WORLD);
}

template <class T>
void recv_vec(std::vector<T>& v) {
  long long n = 0;
  MPI_Recv(&n, 1, MPI_LONG_LONG, 0, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  v.resize(n);
  if (n) MPI_Recv(v.data(), static_cast<int>(n), mpi_type<T>(), 0, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
}

// b (rank 0, whole) -> each rank's block; and back for x.
void scatter_vector(const double* full, long long n, std::vector<double>& local) {
  const int np = mpi_size(), rank = mpi_rank();
  const auto off = contiguous_rows(n, np);
  std::vector<int> counts(np), displs(np);
  for (int r = 0; r < np; ++r) {
    counts[r] = static_cast<int>(off[r + 1] - off[r]);
    displs[r] = static_cast<int>(off[r]);
  }
  local.resize(counts[rank]);
  MPI_Scatterv(full, counts.data(), displs.data(), MPI_DOUBLE, local.data(), counts[rank], MPI_DOUBLE, 0,
               MPI_COMM_WORLD);
}

void gather_vector(const std::vector<double>& local, long long n, double* full) {
  const int np = mpi_size();
  const auto off = contiguous_rows(n, np);
  std::vector<int> counts(np), displs(np);
  for (int r = 0; r < np; ++r) {
    counts[r] = static_cast<int>(off[r + 1] - off[r]);
    displs[r] = static_cast<int>(off[r]);
  }
  MPI_Gatherv(local.data(), static_cast<int>(local.size()), MPI_DOUBLE, full, counts.data(), displs.data(), MPI_DOUBLE,
              0, MPI_COMM_WORLD);
}

long long g_next_id = 1;

class DistributedSolver final : public LinearSolver {
 public:
  DistributedSolver(const std::string& name, const Params& p) : name_(name), tol_(p.linear_tol) {
    id_ = g_next_id++;
    if (mpi_size() > 1) {
      Header h = {kCreate, id_, 0, 0, 0, 0, 0, 0};
      bcast_header(h);
      std::string n = name, text = serialize(p);
      bcast_string(n);
      bcast_string(text);
    }
    kernel_ = make_kernel(name, p);
  }
  ~DistributedSolver() override {
    if (mpi_size() > 1) {
      Header h = {kDestroy, id_, 0, 0, 0, 0, 0, 0};
      bcast_header(h);
    }
  }
  std::string name() const override { return name_; }

  void setup(const SparseMatrix& A, SetupKind kind, const SetupContext& ctx) override {
    if (!A.isCompressed()) throw Error(name_ + ": the matrix must be in compressed CSR form");
    Timer t;
    A_ = &A;
    const int np = mpi_size();
    // Only values travel when the pattern is known to be the same as last time.
    const bool values_only = kind == SetupKind::Values && A.rows() == n_ && A.nonZeros() == nnz_;
    n_ = A.rows();
    nnz_ = A.nonZeros();
    const auto off = contiguous_rows(n_, np);
    if (np > 1) {
      Header h = {kSetup, id_, kind == SetupKind::Values ? 1 : 0, ctx.frame, ctx.substep, ctx.iteration,
                  values_only ? 1 : 0, n_};
      bcast_header(h);
      RowBlock other;
      for (int r = 1; r < np; ++r) {
        extract_block(A, off[r], off[r + 1], other, values_only);
        if (!values_only) {
          send_vec(other.rowptr, r);
          send_vec(other.cols, r);
        }
        send_vec(other.vals, r);
      }
    }
    extract_block(A, off[0], off[1], block_, values_only);
    kernel_->setup(block_, kind, ctx);
    setup_time_ = t.seconds();
  }

  LinearStats solve(const Vector& b, Vector& x) override {
    if (!A_ || b.size() != n_) throw Error(name_ + ": solve() without a matching setup()");
    Timer t;
    std::vector<double> bl, xl;
    if (mpi_size() > 1) {
      Header h = {kSolve, id_, 0, 0, 0, 0, 0, n_};
      bcast_header(h);
      scatter_vector(b.data(), n_, bl);
    } else {
      bl.assign(b.data(), b.data() + b.size());
    }
    LinearStats st = kernel_->solve(bl, xl);
    x.resize(n_);
    if (mpi_size() > 1) gather_vector(xl, n_, x.data());
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
  std::string name_;
  double tol_;
  long long id_ = 0;
  std::unique_ptr<DistributedKernel> kernel_;
  const SparseMatrix* A_ = nullptr;
  long long n_ = -1, nnz_ = -1;
  RowBlock block_;
  double setup_time_ = 0;
};

bool g_workers_stopped = false;
}  // namespace

std::unique_ptr<LinearSolver> make_distributed_solver(const std::string& name, const Params& p) {
  return std::make_unique<DistributedSolver>(name, p);
}

std::unique_ptr<LinearSolver> make_hypre(const Params& p) { return make_distributed_solver("hypre", p); }
std::unique_ptr<LinearSolver> make_muelu(const Params& p) { return make_distributed_solver("muelu", p); }

int serve_workers() {
  std::map<long long, std::unique_ptr<DistributedKernel>> kernels;
  std::map<long long, RowBlock> blocks;
  try {
    for (;;) {
      Header h;
      // Wait for rank 0 without spinning: between solves rank 0 assembles with OpenMP on the
      // same cores, and a busy-polling MPI_Bcast would steal them.
      bcast_header(h);
      const long long id = h[1];
      switch (h[0]) {
        case kCreate: {
          std::string name, text;
          bcast_string(name);
          bcast_string(text);
          kernels[id] = make_kernel(name, deserialize(text));
          break;
        }
        case kSetup: {
          RowBlock& blk = blocks[id];
          const auto off = contiguous_rows(h[7], mpi_size());
          blk.n_global = h[7];
          blk.first = off[mpi_rank()];
          if (!h[6]) {
            recv_vec(blk.rowptr);
            recv_vec(blk.cols);
          }
          recv_vec(blk.vals);
          const SetupKind kind = h[2] ? SetupKind::Values : SetupKind::Structure;
          kernels.at(id)->setup(blk, kind, SetupContext{static_cast<int>(h[3]), static_cast<int>(h[4]),
                                                        static_cast<int>(h[5])});
          break;
        }
        case kSolve: {
          std::vector<double> bl, xl;
          scatter_vector(nullptr, h[7], bl);
          kernels.at(id)->solve(bl, xl);
          gather_vector(xl, h[7], nullptr);
          break;
        }
        case kDestroy:
          kernels.erase(id);
          blocks.erase(id);
          break;
        case kQuit:
          return 0;
        default:
          throw Error("unknown MPI command " + std::to_string(h[0]));
      }
    }
  } catch (const std::exception& e) {
    // A worker cannot report back through the harness: say why and take the job down.
    std::fprintf(stderr, "xpbd-bench (rank %d): %s\n", mpi_rank(), e.what());
    MPI_Abort(MPI_COMM_WORLD, 3);
  }
  return 3;
}

void stop_workers() {
  if (g_workers_stopped || mpi_rank() != 0 || mpi_size() == 1) return;
  g_workers_stopped = true;
  Header h = {kQuit, 0, 0, 0, 0, 0, 0, 0};
  bcast_header(h);
}

#ifdef XB_WITH_MUELU
void finalize_muelu_runtime();
#endif

void finalize_external_libraries() {
#ifdef XB_WITH_MUELU
  finalize_muelu_runtime();
#endif
}

}  // namespace xb
