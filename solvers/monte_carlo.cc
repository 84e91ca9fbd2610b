#include "solvers/monte_carlo.h"

#include <time.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace navtwin {

int MonteCarloWorkers(int runs, int threads) {
  const int wanted = threads > 0 ? threads : static_cast<int>(std::thread::hardware_concurrency());
  return std::max(1, std::min(wanted, runs));
}

void RunParallel(int runs, int threads, const std::function<void(int run, int worker)>& body,
                 const MonteCarloProgress& progress) {
  if (runs < 0) throw std::invalid_argument("RunParallel: negative number of runs " + std::to_string(runs));
  std::atomic<int> next{0};
  std::mutex mutex;  // guards done, error and the progress calls
  int done = 0;
  std::exception_ptr error;

  const auto worker_loop = [&](int worker) {
    for (int run = next.fetch_add(1); run < runs; run = next.fetch_add(1)) {
      try {
        body(run, worker);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::current_exception();
        next.store(runs);  // the other workers take no new run
        return;
      }
      if (progress) {
        const std::lock_guard<std::mutex> lock(mutex);
        progress(++done, runs);
      }
    }
  };

  const int workers = MonteCarloWorkers(runs, threads);
  if (workers == 1) {
    worker_loop(0);
  } else {
    std::vector<std::thread> pool;
    pool.reserve(workers);
    for (int w = 0; w < workers; ++w) pool.emplace_back(worker_loop, w);
    for (std::thread& t : pool) t.join();
  }
  if (error) std::rethrow_exception(error);
}

double ThreadCpuTime_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace navtwin
