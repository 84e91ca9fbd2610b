// Zero-velocity updates as an aiding source: where the stillness rule
// (problems/ins/measurement_rules.h) holds, v_n = 0 (factors/zero_velocity.h); in the
// filter at IMU epochs at most once per interval_s, in the batch at the still states.
#pragma once

#include <memory>

#include "problems/ins/aiding.h"
#include "problems/ins/measurement_rules.h"

namespace navtwin::ins {

/// Count key "zupt".
std::unique_ptr<AidingSource> MakeZuptSource(const ZuptConfig& config);

}  // namespace navtwin::ins
