// How a sweep's jobs are spread (docs/commands.md, `sweep`): over N processes of this program on
// one machine (--jobs N: a queue of job numbers in a pipe that the processes take from, so a slow
// job does not hold up the others), over the ranks of mpirun (they take rank 0's list of jobs one
// by one through a counter file beside the results, harness/io/file_lock.hpp: cmd_sweep.cpp), or
// over the tasks of a cluster's job array (--part K/N: the jobs whose number is K mod N). Every
// process appends its runs to the one results file (harness/io/recorder.hpp) as they end.
#pragma once

#include "args.hpp"

#include <string>
#include <vector>

namespace xb {

// Called by the CLI's main: this process is the xpbd-bench program, which --jobs starts again
// (the Python module is not).
void note_cli_program();

// Under mpirun: whether the ranks share a sweep's jobs: yes when none of its methods is distributed;
// when every one is (hypre, muelu), the ranks serve each of rank 0's solves instead, one job at a
// time, as under `run`. A spec that mixes the two is refused (naming both). False without mpirun.
bool ranks_share_jobs(const std::vector<std::string>& solvers, const std::string& spec_path);
// Every rank calls this: true when `ok` is true on all of them (a rank that failed says why itself).
bool all_ranks(bool ok);

// A part of a sweep's jobs: those whose number (0-based, in sweep order) is k mod n.
struct SweepPart {
  int k = 0, n = 1;
  bool has(int job) const { return job % n == k; }
};
// "K/N" of --part (0 <= K < N). Throws xb::Error naming the flag.
SweepPart parse_part(const std::string& text);

// Whether this process is one of --jobs' workers (XB_SWEEP_QUEUE_FD set by the parent).
bool is_queue_worker();
// A worker's next job number from the queue; -1 when the queue is empty.
int next_queued_job();

// Starts `processes` copies of this program with `argv` (the sweep's own arguments, "sweep" first,
// --jobs removed), hands them the job numbers `todo` through the queue and waits for them all.
// Returns the worst exit code. Throws xb::Error when processes cannot be started.
int run_queue_workers(int processes, const std::vector<int>& todo, const std::vector<std::string>& argv);

}  // namespace xb
