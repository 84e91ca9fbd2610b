// Monte Carlo runs spread over threads and, when navtwin is built with MPI and started by an
// MPI launcher (mpirun, srun), over ranks (docs/cluster.md).
//
// Load balancing is dynamic: whoever is idle takes the next run number (threads on rank 0
// from a shared counter, threads on other ranks by asking rank 0). Rank 0 receives every
// run's record as bytes and hands them to `consume` in run order, so a reduction done
// there adds the runs in the same order whatever the ranks and threads: the results are
// the same bits.
#pragma once

#include <functional>
#include <string>

namespace navtwin::mc {

/// MPI for the life of the object when `use_mpi` and the process was started by an MPI
/// launcher (OMPI_COMM_WORLD_SIZE, PMIX_RANK or PMI_RANK set) and navtwin has MPI
/// (NAVTWIN_WITH_MPI); otherwise one process (rank 0 of 1). At most one at a time.
class RankSession {
 public:
  explicit RankSession(bool use_mpi = true);
  ~RankSession();
  RankSession(const RankSession&) = delete;
  RankSession& operator=(const RankSession&) = delete;

  int rank() const { return rank_; }
  int ranks() const { return ranks_; }
  bool mpi() const { return mpi_; }
  /// Ends every rank at once (MPI_Abort) after `message` on stderr; exit(code) without MPI.
  [[noreturn]] void Abort(const std::string& message, int code) const;

 private:
  int rank_ = 0;
  int ranks_ = 1;
  bool mpi_ = false;
};

/// True when this build can use MPI.
bool BuiltWithMpi();

/// Computes compute(run) for every run in [0, runs) on MonteCarloWorkers(runs, threads)
/// threads per rank and, on rank 0, calls consume(run, bytes) for each in run order (one
/// call at a time, from any thread) and progress(done, runs) after each. Returns on every
/// rank once all runs are consumed. An exception from compute on rank 0 stops the runs
/// and is rethrown there; on another rank it aborts every rank with its message.
void DistributeRuns(const RankSession& session, int runs, int threads,
                    const std::function<std::string(int run)>& compute,
                    const std::function<void(int run, const std::string& bytes)>& consume,
                    const std::function<void(int done, int runs)>& progress);

}  // namespace navtwin::mc
