// Reading the transfer-alignment configuration (config.h). One flat YAML mapping whose
// keys are the member names of TransferConfig (units in the names); every key is optional
// and keeps the default of config.h when absent. Unknown keys, wrong types and values out
// of range are InputError naming the file, the line and the key (core/config/yaml_config.h).
#include "problems/transfer_alignment/config.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "core/io/input_error.h"
#include "core/config/yaml_config.h"
#include "core/units.h"

namespace navtwin::transfer {
namespace {

TransferConfig ParseRoot(const ConfigNode& n) {
  n.RequireKeys({"gyro_bias_deg_h", "gyro_arw_deg_sqrt_h", "accel_bias_ug", "accel_vrw_m_s_sqrt_h",
                 "gyro_scale_factor_ppm", "accel_scale_factor_ppm", "gyro_axis_misalignment_arcsec",
                 "accel_axis_misalignment_arcsec",
                 "initial_velocity_mps", "initial_attitude_deg", "misalignment_deg", "delay_s", "delay_initial_s",
                 "master_attitude_mrad", "master_velocity_mps", "master_fit_window_s", "lever_arm_b_m", "settle_s",
                 "batch_state_interval_s", "batch_max_iterations", "history_window_s"});
  TransferConfig c;
  // Slave sensor: biases and noise densities may be 0 (a sensor without that error).
  c.gyro_bias_radps = n.NonNegativeSi("gyro_bias_deg_h", kDegPerHour_radps, c.gyro_bias_radps);
  c.gyro_arw_rad_per_sqrt_s =
      n.NonNegativeSi("gyro_arw_deg_sqrt_h", kDegPerSqrtHour_radpsqrts, c.gyro_arw_rad_per_sqrt_s);
  c.accel_bias_mps2 = n.NonNegativeSi("accel_bias_ug", kMicroG_mps2, c.accel_bias_mps2);
  c.accel_vrw_mps_per_sqrt_s =
      n.NonNegativeSi("accel_vrw_m_s_sqrt_h", kMpsPerSqrtHour_mpspsqrts, c.accel_vrw_mps_per_sqrt_s);
  c.gyro_scale_factor = n.NonNegativeSi("gyro_scale_factor_ppm", kPpm, c.gyro_scale_factor);
  c.accel_scale_factor = n.NonNegativeSi("accel_scale_factor_ppm", kPpm, c.accel_scale_factor);
  c.gyro_axis_misalignment_rad =
      n.NonNegativeSi("gyro_axis_misalignment_arcsec", kArcsec_rad, c.gyro_axis_misalignment_rad);
  c.accel_axis_misalignment_rad =
      n.NonNegativeSi("accel_axis_misalignment_arcsec", kArcsec_rad, c.accel_axis_misalignment_rad);
  // Initial standard deviations: diagonal entries of P0, so > 0.
  c.initial_velocity_mps = n.Positive("initial_velocity_mps", c.initial_velocity_mps);
  c.initial_attitude_rad = n.PositiveSi("initial_attitude_deg", kDegToRad, c.initial_attitude_rad);
  c.misalignment_rad = n.PositiveSi("misalignment_deg", kDegToRad, c.misalignment_rad);
  c.delay_s = n.Positive("delay_s", c.delay_s);
  // The delay's initial guess: a time shift, any finite value (the reader checks finiteness).
  c.delay_initial_s = n.Double("delay_initial_s", c.delay_initial_s);
  if (!std::isfinite(c.delay_initial_s)) n.Fail("delay_initial_s", "must be finite");
  // Master measurement noise: the R matrix of the filter and the batch's whitening, so > 0.
  c.master_attitude_rad = n.PositiveSi("master_attitude_mrad", kMrad_rad, c.master_attitude_rad);
  c.master_velocity_mps = n.Positive("master_velocity_mps", c.master_velocity_mps);
  c.master_fit_window_s = n.NonNegative("master_fit_window_s", c.master_fit_window_s);
  c.lever_arm_b_m = n.Vector("lever_arm_b_m", c.lever_arm_b_m);
  if (!c.lever_arm_b_m.allFinite()) n.Fail("lever_arm_b_m", "must be finite");
  c.settle_s = n.NonNegative("settle_s", c.settle_s);
  c.batch_state_interval_s = n.Positive("batch_state_interval_s", c.batch_state_interval_s);
  c.batch_max_iterations = n.Int("batch_max_iterations", c.batch_max_iterations, 1, 100000);
  c.history_window_s = n.Positive("history_window_s", c.history_window_s);
  return c;
}

}  // namespace

TransferConfig LoadTransferConfig(const std::string& path) { return ParseRoot(LoadYamlFile(path)); }

TransferConfig ParseTransferConfig(const std::string& yaml_text, const std::string& file) {
  return ParseRoot(ParseYaml(yaml_text, file));
}

}  // namespace navtwin::transfer
