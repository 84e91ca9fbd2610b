// The aided-INS layer's names (problems/ins) that this problem uses throughout.
#pragma once

#include "problems/ins/imu_noise.h"
#include "problems/ins/ins_state.h"
#include "problems/ins/measurement_rules.h"
#include "problems/ins/sources/baro.h"
#include "problems/ins/sources/gnss.h"
#include "problems/ins/sources/mag.h"
#include "problems/ins/sources/nhc.h"

namespace navtwin::gnss_ins {

namespace err = ins::err;
using ins::BaroConfig;
using ins::GnssConfig;
using ins::ImuErrors;
using ins::ImuNoise;
using ins::InsState;
using ins::MagConfig;
using ins::NavEpoch;
using ins::NhcConfig;
using ins::VehicleConfig;
using ins::ZuptConfig;

}  // namespace navtwin::gnss_ins
