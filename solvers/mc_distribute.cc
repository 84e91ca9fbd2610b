#include "solvers/mc_distribute.h"

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

#ifdef NAVTWIN_WITH_MPI
#include <mpi.h>
#endif

#include "solvers/monte_carlo.h"

namespace navtwin::mc {

namespace {

/// Hands out run numbers in chunks, guided: a quarter of the remaining runs per worker,
/// at least one, so the last chunks are small and the workers finish together.
class RunDispenser {
 public:
  RunDispenser(int runs, int workers) : runs_(runs), workers_(workers) {}
  /// The next chunk [first, first + count); count 0 when there is none left.
  std::pair<int, int> Take() {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (stopped_ || next_ >= runs_) return {runs_, 0};
    const int count = std::max(1, (runs_ - next_) / (4 * workers_));
    const int first = next_;
    next_ += count;
    return {first, count};
  }
  void Stop() {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopped_ = true;
  }
  bool stopped() {
    const std::lock_guard<std::mutex> lock(mutex_);
    return stopped_;
  }

 private:
  std::mutex mutex_;
  int runs_, workers_;
  int next_ = 0;
  bool stopped_ = false;
};

/// Passes records to `consume` in run order as they arrive in any order.
class InRunOrder {
 public:
  InRunOrder(int runs, const std::function<void(int, const std::string&)>& consume,
             const std::function<void(int, int)>& progress)
      : runs_(runs), consume_(consume), progress_(progress) {}
  void Deliver(int run, std::string bytes) {
    const std::lock_guard<std::mutex> lock(mutex_);
    pending_.emplace(run, std::move(bytes));
    for (auto it = pending_.find(next_); it != pending_.end(); it = pending_.find(next_)) {
      consume_(next_, it->second);
      pending_.erase(it);
      ++next_;
      if (progress_) progress_(next_, runs_);
    }
  }

 private:
  std::mutex mutex_;
  int runs_;
  const std::function<void(int, const std::string&)>& consume_;
  const std::function<void(int, int)>& progress_;
  std::map<int, std::string> pending_;
  int next_ = 0;
};

bool StartedByMpiLauncher() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"}) {
    if (std::getenv(name) != nullptr) return true;
  }
  return false;
}

#ifdef NAVTWIN_WITH_MPI
constexpr int kTagResults = 1;  // worker -> rank 0: the finished chunk's records
constexpr int kTagChunk = 2;    // rank 0 -> worker: the next chunk (first, count)

void AppendRecord(std::string* payload, std::int64_t run, const std::string& bytes) {
  const std::uint64_t n = bytes.size();
  payload->append(reinterpret_cast<const char*>(&run), sizeof run);
  payload->append(reinterpret_cast<const char*>(&n), sizeof n);
  *payload += bytes;
}

void DeliverPayload(const std::string& payload, InRunOrder* order) {
  std::size_t at = 0;
  while (at + 16 <= payload.size()) {
    std::int64_t run = 0;
    std::uint64_t n = 0;
    std::memcpy(&run, payload.data() + at, 8);
    std::memcpy(&n, payload.data() + at + 8, 8);
    at += 16;
    if (n > payload.size() - at) throw std::runtime_error("Monte Carlo: truncated message from a rank");
    order->Deliver(static_cast<int>(run), payload.substr(at, n));
    at += n;
  }
}

/// Rank 0's main thread: answers every other rank's threads until each got "no more".
void ServeRanks(int remote_workers, RunDispenser* dispenser, InRunOrder* order) {
  int stopped = 0;
  while (stopped < remote_workers) {
    int arrived = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, kTagResults, MPI_COMM_WORLD, &arrived, &status);
    if (!arrived) {
      // Polling with a short sleep leaves the core to the workers (a blocking probe spins).
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      continue;
    }
    int count = 0;
    MPI_Get_count(&status, MPI_BYTE, &count);
    std::string payload(static_cast<std::size_t>(count), '\0');
    MPI_Recv(payload.data(), count, MPI_BYTE, status.MPI_SOURCE, kTagResults, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    DeliverPayload(payload, order);
    const std::pair<int, int> chunk = dispenser->Take();
    const std::int64_t reply[2] = {chunk.first, chunk.second};
    MPI_Send(reply, 2, MPI_INT64_T, status.MPI_SOURCE, kTagChunk, MPI_COMM_WORLD);
    if (chunk.second == 0) ++stopped;
  }
}

/// A thread of a rank other than 0: asks for chunks, computes them, sends their records.
void RemoteWorker(const RankSession& session, std::mutex* mpi_mutex,
                  const std::function<std::string(int)>& compute) {
  std::string payload;
  for (;;) {
    std::int64_t chunk[2] = {0, 0};
    {
      const std::lock_guard<std::mutex> lock(*mpi_mutex);
      MPI_Send(payload.data(), static_cast<int>(payload.size()), MPI_BYTE, 0, kTagResults, MPI_COMM_WORLD);
      MPI_Recv(chunk, 2, MPI_INT64_T, 0, kTagChunk, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    }
    if (chunk[1] == 0) return;
    payload.clear();
    for (std::int64_t run = chunk[0]; run < chunk[0] + chunk[1]; ++run) {
      try {
        AppendRecord(&payload, run, compute(static_cast<int>(run)));
      } catch (const std::exception& e) {
        session.Abort("navtwin mc: rank " + std::to_string(session.rank()) + ", run " + std::to_string(run) +
                          ": " + e.what(),
                      1);
      }
    }
  }
}
#endif

}  // namespace

bool BuiltWithMpi() {
#ifdef NAVTWIN_WITH_MPI
  return true;
#else
  return false;
#endif
}

RankSession::RankSession(bool use_mpi) {
#ifdef NAVTWIN_WITH_MPI
  if (!use_mpi || !StartedByMpiLauncher()) return;
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &provided);
  mpi_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks_);
  if (provided < MPI_THREAD_SERIALIZED) {
    Abort("navtwin mc: this MPI library cannot serve threads (MPI_THREAD_SERIALIZED unavailable)", 1);
  }
#else
  if (use_mpi && StartedByMpiLauncher()) {
    std::cerr << "navtwin: started by an MPI launcher, but built without MPI: every rank computes "
                 "alone (rebuild with libopenmpi-dev installed)\n";
  }
#endif
}

RankSession::~RankSession() {
#ifdef NAVTWIN_WITH_MPI
  if (mpi_) MPI_Finalize();
#endif
}

void RankSession::Abort(const std::string& message, int code) const {
  std::cerr << message << std::endl;
#ifdef NAVTWIN_WITH_MPI
  if (mpi_) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  std::exit(code);
}

void DistributeRuns(const RankSession& session, int runs, int threads,
                    const std::function<std::string(int run)>& compute,
                    const std::function<void(int run, const std::string& bytes)>& consume,
                    const std::function<void(int done, int runs)>& progress) {
  if (runs < 0) throw std::invalid_argument("Monte Carlo: negative number of runs");
  const int workers = MonteCarloWorkers(std::max(runs, 1), threads);
#ifdef NAVTWIN_WITH_MPI
  if (session.rank() != 0) {
    std::mutex mpi_mutex;
    std::vector<std::thread> pool;
    for (int w = 0; w < workers; ++w) pool.emplace_back(RemoteWorker, std::cref(session), &mpi_mutex, std::cref(compute));
    for (std::thread& t : pool) t.join();
    return;
  }
#endif
  RunDispenser dispenser(runs, workers * session.ranks());
  InRunOrder order(runs, consume, progress);
  std::mutex error_mutex;
  std::exception_ptr error;
  const auto local_worker = [&]() {
    for (std::pair<int, int> chunk = dispenser.Take(); chunk.second > 0; chunk = dispenser.Take()) {
      for (int run = chunk.first; run < chunk.first + chunk.second && !dispenser.stopped(); ++run) {
        try {
          order.Deliver(run, compute(run));
        } catch (...) {
          const std::lock_guard<std::mutex> lock(error_mutex);
          if (!error) error = std::current_exception();
          dispenser.Stop();
          return;
        }
      }
    }
  };
  const bool serve = session.mpi() && session.ranks() > 1;
  if (workers == 1 && !serve) {
    local_worker();
  } else {
    std::vector<std::thread> pool;
    for (int w = 0; w < workers; ++w) pool.emplace_back(local_worker);
#ifdef NAVTWIN_WITH_MPI
    if (serve) ServeRanks((session.ranks() - 1) * workers, &dispenser, &order);
#endif
    for (std::thread& t : pool) t.join();
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace navtwin::mc
