#include "sweep_jobs.hpp"

#include "../../core/error.hpp"
#include "../../solvers/mpi/distributed_kernel.hpp"
#include "../../solvers/mpi/partition.hpp"

#include <mpi.h>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>

extern char** environ;

namespace xb {

namespace {

constexpr const char* queue_variable = "XB_SWEEP_QUEUE_FD";

// The environment as the program started, before MPI_Init: MPI's singleton start adds variables
// (OMPI_*, PMIX_*) that would make a child believe it is a rank of this process's job.
const std::vector<std::string> start_environment = [] {
  std::vector<std::string> env;
  for (char** e = environ; e && *e; ++e)
    if (std::strncmp(*e, queue_variable, std::strlen(queue_variable)) != 0) env.emplace_back(*e);
  return env;
}();

bool cli_program = false;

// Blocking write of all n bytes; false when no worker reads any more (they all ended).
bool write_all(int fd, const void* data, size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t k = ::write(fd, p, n);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    p += k;
    n -= static_cast<size_t>(k);
  }
  return true;
}

}  // namespace

void note_cli_program() { cli_program = true; }

bool ranks_share_jobs(const std::vector<std::string>& solvers, const std::string& spec_path) {
  if (mpi_size() == 1) return false;
  std::string distributed, local;
  for (const auto& name : solvers) {
    std::string& list = method_is_distributed(name) ? distributed : local;
    list += (list.empty() ? "" : ", ") + name;
  }
  if (!distributed.empty() && !local.empty())
    throw Error("sweep: " + spec_path + ": under mpirun a sweep's methods are all distributed (the ranks share each "
                "solve) or none is (the ranks share the jobs); this one mixes " + distributed + " with " + local +
                ": run them as two sweeps");
  return distributed.empty();
}

bool all_ranks(bool ok) {
  if (mpi_size() == 1) return ok;
  int mine = ok ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  return all == 1;
}

SweepPart parse_part(const std::string& text) {
  const size_t slash = text.find('/');
  char *e1 = nullptr, *e2 = nullptr;
  if (slash != std::string::npos) {
    const std::string a = text.substr(0, slash), b = text.substr(slash + 1);
    const long k = std::strtol(a.c_str(), &e1, 10), n = std::strtol(b.c_str(), &e2, 10);
    if (!a.empty() && !b.empty() && *e1 == '\0' && *e2 == '\0' && n >= 1 && n <= 1000000 && k >= 0 && k < n)
      return SweepPart{static_cast<int>(k), static_cast<int>(n)};
  }
  throw Error("sweep: --part " + text + ": expected K/N with 0 <= K < N (this process runs the jobs whose number is K mod N)");
}

bool is_queue_worker() { return std::getenv(queue_variable) != nullptr; }

int next_queued_job() {
  static const int fd = [] {
    // "FD:PID": the queue's read end and the parent, whose end (a kill included) ends this worker too.
    const char* v = std::getenv(queue_variable);
    if (!v) return -1;
    const char* colon = std::strchr(v, ':');
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (colon && ::getppid() != static_cast<pid_t>(std::atol(colon + 1))) std::_Exit(0);  // gone already
    return std::atoi(v);
  }();
  if (fd < 0) return -1;
  // The parent writes 4-byte numbers, each in one write (atomic on a pipe), so one read of 4
  // bytes takes exactly one job, and no two workers the same.
  std::int32_t job = 0;
  size_t got = 0;
  while (got < sizeof job) {
    const ssize_t k = ::read(fd, reinterpret_cast<char*>(&job) + got, sizeof job - got);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return -1;  // the parent closed it: no more jobs
    got += static_cast<size_t>(k);
  }
  return job;
}

int run_queue_workers(int processes, const std::vector<int>& todo, const std::vector<std::string>& argv) {
  if (!cli_program)
    throw Error("sweep: --jobs starts copies of the xpbd-bench program: run it from the command line (from Python: subprocess)");
  int queue[2];
  if (::pipe2(queue, O_CLOEXEC) != 0) throw Error(std::string("sweep: --jobs: cannot make a pipe: ") + std::strerror(errno));
  ::fcntl(queue[0], F_SETFD, 0);  // the read end goes to the workers, the write end stays here
  std::vector<std::string> env = start_environment;
  env.push_back(std::string(queue_variable) + "=" + std::to_string(queue[0]) + ":" + std::to_string(::getpid()));
  // N processes share the cores: each gets its share of OpenMP threads, unless the user chose
  // (OMP_NUM_THREADS; a spec's `threads` overrides both).
  if (std::none_of(env.begin(), env.end(), [](const std::string& e) { return e.rfind("OMP_NUM_THREADS=", 0) == 0; }))
    env.push_back("OMP_NUM_THREADS=" + std::to_string(std::max(1L, ::sysconf(_SC_NPROCESSORS_ONLN) / processes)));
  std::vector<char*> envp, args;
  for (auto& e : env) envp.push_back(e.data());
  envp.push_back(nullptr);
  std::vector<std::string> argv_copy = argv;
  std::string program = "xpbd-bench";
  args.push_back(program.data());
  for (auto& a : argv_copy) args.push_back(a.data());
  args.push_back(nullptr);
  std::vector<pid_t> pids;
  for (int i = 0; i < processes; ++i) {
    pid_t pid = 0;
    const int e = ::posix_spawn(&pid, "/proc/self/exe", nullptr, nullptr, args.data(), envp.data());
    if (e != 0) {
      ::close(queue[0]);
      ::close(queue[1]);  // the workers started so far see an empty queue and end
      for (pid_t p : pids) ::waitpid(p, nullptr, 0);
      throw Error(std::string("sweep: --jobs: cannot start a process: ") + std::strerror(e));
    }
    pids.push_back(pid);
  }
  ::close(queue[0]);
  // A full pipe blocks here until the workers take jobs; if they all end early, the write fails
  // (EPIPE, with SIGPIPE ignored meanwhile) and the rest is left for a rerun to resume.
  struct sigaction ignore {}, saved {};
  ignore.sa_handler = SIG_IGN;
  ::sigaction(SIGPIPE, &ignore, &saved);
  for (int job : todo) {
    const std::int32_t j = job;
    if (!write_all(queue[1], &j, sizeof j)) break;
  }
  ::close(queue[1]);
  ::sigaction(SIGPIPE, &saved, nullptr);
  int worst = 0;
  for (pid_t p : pids) {
    int status = 0;
    while (::waitpid(p, &status, 0) < 0 && errno == EINTR) {
    }
    const int rc = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    worst = std::max(worst, rc);
  }
  return worst;
}

}  // namespace xb
