// The registration of the aiding sources of a GNSS/INS run.
#pragma once

#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/inputs.h"
#include "problems/ins/aiding.h"

namespace navtwin::gnss_ins {

/// The aiding sources of a GNSS/INS run, in the order the estimators process them at an
/// epoch: GNSS, magnetometer, barometer, ZUPT, then the vehicle constraints when enabled
/// (problems/gnss_ins/sources.cc, the one place that names them). Fresh sources per run:
/// they keep filter-side state.
ins::AidingSources MakeSources(const Inputs& inputs, const GnssInsConfig& config);

}  // namespace navtwin::gnss_ins
