// Messages between rank 0 and the worker ranks: see distributed_transport.hpp.
#include "distributed_transport.hpp"

#include "../../core/error.hpp"
#include "../solver_settings.hpp"

#include <chrono>
#include <sstream>
#include <thread>

namespace xb {

namespace {
constexpr int kHeaderWords = sizeof(Header) / sizeof(long long);
static_assert(sizeof(Header) == kHeaderWords * sizeof(long long), "Header is broadcast as long longs");

template <class T>
MPI_Datatype mpi_type();
template <>
MPI_Datatype mpi_type<int>() { return MPI_INT; }
template <>
MPI_Datatype mpi_type<long long>() { return MPI_LONG_LONG; }
template <>
MPI_Datatype mpi_type<double>() { return MPI_DOUBLE; }

template <class T>
void send_vec(const T* v, long long n, int to) {
  MPI_Send(&n, 1, MPI_LONG_LONG, to, 0, MPI_COMM_WORLD);
  if (n) MPI_Send(v, static_cast<int>(n), mpi_type<T>(), to, 0, MPI_COMM_WORLD);
}
template <class T>
void send_vec(const std::vector<T>& v, int to) { send_vec(v.data(), static_cast<long long>(v.size()), to); }

template <class T>
void recv_vec(std::vector<T>& v) {
  long long n = 0;
  MPI_Recv(&n, 1, MPI_LONG_LONG, 0, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  v.resize(n);
  if (n) MPI_Recv(v.data(), static_cast<int>(n), mpi_type<T>(), 0, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
}

// Each rank's row count and first row, for Scatterv/Gatherv.
void counts_and_displs(long long n, int block_size, std::vector<int>& counts, std::vector<int>& displs) {
  const int np = mpi_size();
  const auto off = contiguous_rows(n, np, block_size);
  counts.resize(np);
  displs.resize(np);
  for (int r = 0; r < np; ++r) {
    counts[r] = static_cast<int>(off[r + 1] - off[r]);
    displs[r] = static_cast<int>(off[r]);
  }
}
}  // namespace

// Blocking and non-blocking collectives must not be mixed: every header goes through Ibcast.
void bcast_header(Header& h) {
  MPI_Request req;
  MPI_Ibcast(&h, kHeaderWords, MPI_LONG_LONG, 0, MPI_COMM_WORLD, &req);
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

std::string agree_on_errors(const std::string& local_error) {
  int mine = local_error.empty() ? 0 : 1, any = 0;
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (!any) return "";
  const int np = mpi_size(), rank = mpi_rank();
  int len = static_cast<int>(local_error.size());
  std::vector<int> lens(np), displs(np, 0);
  MPI_Gather(&len, 1, MPI_INT, lens.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  for (int r = 1; r < np; ++r) displs[r] = displs[r - 1] + lens[r - 1];
  std::string all(rank == 0 ? displs[np - 1] + lens[np - 1] : 0, '\0');
  MPI_Gatherv(local_error.data(), len, MPI_CHAR, all.data(), lens.data(), displs.data(), MPI_CHAR, 0, MPI_COMM_WORLD);
  if (rank != 0) return "failed";
  for (int r = 0; r < np; ++r)
    if (lens[r] > 0) return (r == 0 ? "" : "rank " + std::to_string(r) + ": ") + all.substr(displs[r], lens[r]);
  return "failed";
}

std::string serialize_settings(const SolverSettings& p) {
  std::string s;
  for (const auto& f : solver_settings()) s += f.key + "=" + setting_text(f, p) + "\n";
  return s;
}

SolverSettings deserialize_settings(const std::string& text) {
  SolverSettings p;
  std::istringstream is(text);
  for (std::string line; std::getline(is, line);) {
    const auto eq = line.find('=');
    if (eq != std::string::npos) set_setting(solver_settings(), p, line.substr(0, eq), line.substr(eq + 1), "mpi");
  }
  return p;
}

void extract_block(const SparseMatrix& A, const Eigen::MatrixXd* nk, long long first, long long last, int block_size,
                   RowBlock& blk, bool values_only) {
  const int* op = A.outerIndexPtr();
  const int* ii = A.innerIndexPtr();
  const double* vv = A.valuePtr();
  const long long b0 = op[first], b1 = op[last];
  blk.n_global = A.rows();
  blk.first = first;
  blk.block_size = block_size;
  blk.vals.assign(vv + b0, vv + b1);
  // The basis changes with the positions: it travels with every setup, values-only ones too.
  if (nk) blk.near_kernel = nk->middleRows(first, last - first);
  else blk.near_kernel.resize(last - first, 0);
  if (values_only) return;
  blk.rowptr.resize(last - first + 1);
  for (long long i = first; i <= last; ++i) blk.rowptr[i - first] = static_cast<int>(op[i] - b0);
  blk.cols.assign(ii + b0, ii + b1);
}

void send_block(const RowBlock& blk, int to, bool values_only) {
  if (!values_only) {
    send_vec(blk.rowptr, to);
    send_vec(blk.cols, to);
  }
  send_vec(blk.vals, to);
  send_vec(blk.near_kernel.data(), static_cast<long long>(blk.near_kernel.size()), to);
}

void recv_block(RowBlock& blk, bool values_only, long long near_kernel_cols) {
  if (!values_only) {
    recv_vec(blk.rowptr);
    recv_vec(blk.cols);
  }
  recv_vec(blk.vals);
  std::vector<double> nk;
  recv_vec(nk);
  if (static_cast<long long>(nk.size()) != blk.rows() * near_kernel_cols)
    throw Error("near-kernel block of " + std::to_string(nk.size()) + " values for " + std::to_string(blk.rows()) +
                " rows and " + std::to_string(near_kernel_cols) + " columns");
  blk.near_kernel = Eigen::Map<const Eigen::MatrixXd>(nk.data(), blk.rows(), near_kernel_cols);
}

void scatter_vector(const double* full, long long n, int block_size, std::vector<double>& local) {
  std::vector<int> counts, displs;
  counts_and_displs(n, block_size, counts, displs);
  const int rank = mpi_rank();
  local.resize(counts[rank]);
  MPI_Scatterv(full, counts.data(), displs.data(), MPI_DOUBLE, local.data(), counts[rank], MPI_DOUBLE, 0,
               MPI_COMM_WORLD);
}

void gather_vector(const std::vector<double>& local, long long n, int block_size, double* full) {
  std::vector<int> counts, displs;
  counts_and_displs(n, block_size, counts, displs);
  MPI_Gatherv(local.data(), static_cast<int>(local.size()), MPI_DOUBLE, full, counts.data(), displs.data(), MPI_DOUBLE,
              0, MPI_COMM_WORLD);
}

}  // namespace xb
