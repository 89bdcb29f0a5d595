// The messages between rank 0 and the worker ranks of the distributed solvers (internal to
// distributed.cpp): command headers, SolverSettings, row blocks with their near-kernel rows, vectors.
#pragma once

#include "partition.hpp"
#include "../../core/sparse.hpp"
#include "../solver_settings.hpp"

#include <string>
#include <vector>

namespace xb {

enum Cmd : long long { kCreate = 1, kSetup, kSolve, kDestroy, kQuit };

// Every command starts with this header, broadcast from rank 0.
struct Header {
  long long cmd = 0, id = 0;
  long long values = 0;       // setup: SetupKind::Values
  long long frame = 0, substep = 0, iteration = 0;
  long long values_only = 0;  // setup: only the values travel (same pattern as last time)
  long long n_global = 0;     // setup, solve
  long long block_size = 1;   // setup, solve
  long long near_kernel_cols = 0;  // setup
  long long tol_bits = 0;     // solve: the relative tolerance, a double's bits
};

// Non-blocking broadcast; waiting ranks sleep between tests instead of spinning.
void bcast_header(Header& h);
void bcast_string(std::string& s);

// Collective: every rank passes what went wrong on it ("" = nothing). Returns "" on every rank
// when nothing did; else a non-empty text on every rank, on rank 0 the first failing rank's
// message ("rank R: ..." for a worker), so that rank 0 can record it as the run's error.
std::string agree_on_errors(const std::string& local_error);

// The solver settings as "key=value" lines through their one table (so workers see exactly rank 0's).
std::string serialize_settings(const SolverSettings& p);
SolverSettings deserialize_settings(const std::string& text);

// Rank 0: rows [first, last) of A, and of the near-kernel basis when nk is not null, into blk.
void extract_block(const SparseMatrix& A, const Eigen::MatrixXd* nk, long long first, long long last, int block_size,
                   RowBlock& blk, bool values_only);
// Rank 0 → rank `to`: the parts of blk that travel for this setup; a worker receives them.
void send_block(const RowBlock& blk, int to, bool values_only);
void recv_block(RowBlock& blk, bool values_only, long long near_kernel_cols);

// b (rank 0, whole) → each rank's rows; and back for x. `full` is only read/written on rank 0.
void scatter_vector(const double* full, long long n, int block_size, std::vector<double>& local);
void gather_vector(const std::vector<double>& local, long long n, int block_size, double* full);

}  // namespace xb
