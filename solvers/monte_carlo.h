// Problem-agnostic Monte Carlo runner: runs = independent trials spread over worker
// threads that take the next run number from a shared atomic counter (so fast and slow
// runs balance themselves).
//
// Determinism: the runner only decides which worker executes a run, never what the run
// computes. A body that draws from its own generator for each run (e.g.
// sim::Rng(seed).Stream("run " + std::to_string(run))), writes its result into the slot of
// that run and leaves the reduction to the caller (in run order, after RunParallel
// returns) gives bit-identical results for every thread count.
#pragma once

#include <functional>

namespace navtwin {

/// Called as runs complete: runs done so far (1..runs, increasing) and the total. Called
/// from the worker threads, one call at a time.
using MonteCarloProgress = std::function<void(int done, int runs)>;

/// The number of workers RunParallel uses: `threads` (<= 0: std::thread's hardware
/// concurrency, at least 1), never more than `runs`, at least 1.
int MonteCarloWorkers(int runs, int threads);

/// Executes body(run, worker) exactly once for every run in [0, runs) on
/// MonteCarloWorkers(runs, threads) threads; worker in [0, workers) identifies the thread
/// (for per-worker scratch or accumulators). With one worker the calling thread does the
/// work. The first exception a body throws stops the remaining runs and is rethrown here
/// once every worker has stopped. runs < 0 throws std::invalid_argument.
void RunParallel(int runs, int threads, const std::function<void(int run, int worker)>& body,
                 const MonteCarloProgress& progress = nullptr);

/// CPU time consumed so far by the calling thread (s): differences of it time one thread's
/// work without counting what other threads or processes do on the same cores.
double ThreadCpuTime_s();

}  // namespace navtwin
