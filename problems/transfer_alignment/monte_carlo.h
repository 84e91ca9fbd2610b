// Transfer alignment under `navtwin mc --problem transfer` and `navtwin bound --problem
// transfer` (docs/monte-carlo.md, docs/accuracy-bound.md).
//
// Quantities per method (errors estimate - truth, on a grid of whole seconds after the
// slave's start; at each point the method's latest estimate at or before it):
//   misalignment      Log(M_est M_true^T), 3 (x, y, z of the master body), mrad, with the
//                     reported sigma (the final point: the full 3 x 3 block);
//   delay             tau_est - tau_true, ms, with the reported sigma;
//   misalignment_delay  the final joint (misalignment, delay) with its 4 x 4 covariance, SI
//                     (rad, s): its NEES is the one TransferResult::nees_misalignment_delay has;
//   attitude          the slave attitude error (roll, pitch, heading), mrad, no sigma.
#pragma once

#include <cstdint>
#include <vector>

#include "core/sim/scenario.h"
#include "problems/transfer_alignment/config.h"
#include "problems/transfer_alignment/run.h"
#include "solvers/mc_record.h"

namespace navtwin::transfer {

/// Run `run` of an experiment: the scenario simulated with `seed`, each method run on it.
/// A method that throws is recorded as failed (its message), not passed on.
mc::RunRecord TransferMcRun(const sim::Scenario& scenario, const TransferConfig& config,
                            const std::vector<Method>& methods, std::uint64_t seed, int run);

/// The Cramér-Rao bound of the scenario (docs/accuracy-bound.md): the batch's covariance
/// at the truth, from the scenario simulated with every sensor error off and the
/// configured noise; quantities misalignment, delay and misalignment_delay at the final
/// grid point (they are constants of the flight). Throws when the batch fails.
mc::MethodRecord TransferBound(const sim::Scenario& scenario, const TransferConfig& config, std::uint64_t seed);

}  // namespace navtwin::transfer
