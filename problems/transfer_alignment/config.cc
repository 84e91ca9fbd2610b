// Reading the transfer-alignment configuration (config.h). One flat YAML mapping whose
// keys are the member names of TransferConfig (units in the names); every key is optional
// and keeps the default of config.h when absent. Unknown keys, wrong types and values out
// of range are InputError naming the file, the line and the key (core/sim/yaml_config.h).
#include "problems/transfer_alignment/config.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "core/io/input_error.h"
#include "core/sim/yaml_config.h"

namespace navtwin::transfer {
namespace {

using sim::ConfigNode;

TransferConfig ParseRoot(const ConfigNode& n) {
  n.RequireKeys({"gyro_bias_deg_h", "gyro_arw_deg_sqrt_h", "accel_bias_ug", "accel_vrw_m_s_sqrt_h",
                 "initial_velocity_mps", "initial_attitude_deg", "misalignment_deg", "delay_s", "delay_initial_s",
                 "master_attitude_mrad", "master_velocity_mps", "master_fit_window_s", "lever_arm_b_m", "settle_s",
                 "batch_state_interval_s", "batch_max_iterations"});
  TransferConfig c;
  // Slave sensor: biases and noise densities may be 0 (a sensor without that error).
  c.gyro_bias_deg_h = n.NonNegative("gyro_bias_deg_h", c.gyro_bias_deg_h);
  c.gyro_arw_deg_sqrt_h = n.NonNegative("gyro_arw_deg_sqrt_h", c.gyro_arw_deg_sqrt_h);
  c.accel_bias_ug = n.NonNegative("accel_bias_ug", c.accel_bias_ug);
  c.accel_vrw_m_s_sqrt_h = n.NonNegative("accel_vrw_m_s_sqrt_h", c.accel_vrw_m_s_sqrt_h);
  // Initial standard deviations: diagonal entries of P0, so > 0.
  c.initial_velocity_mps = n.Positive("initial_velocity_mps", c.initial_velocity_mps);
  c.initial_attitude_deg = n.Positive("initial_attitude_deg", c.initial_attitude_deg);
  c.misalignment_deg = n.Positive("misalignment_deg", c.misalignment_deg);
  c.delay_s = n.Positive("delay_s", c.delay_s);
  // The delay's initial guess: a time shift, any finite value (the reader checks finiteness).
  c.delay_initial_s = n.Double("delay_initial_s", c.delay_initial_s);
  if (!std::isfinite(c.delay_initial_s)) n.Fail("delay_initial_s", "must be finite");
  // Master measurement noise: the R matrix of the filter and the batch's whitening, so > 0.
  c.master_attitude_mrad = n.Positive("master_attitude_mrad", c.master_attitude_mrad);
  c.master_velocity_mps = n.Positive("master_velocity_mps", c.master_velocity_mps);
  c.master_fit_window_s = n.NonNegative("master_fit_window_s", c.master_fit_window_s);
  c.lever_arm_b_m = n.Vector("lever_arm_b_m", c.lever_arm_b_m);
  if (!c.lever_arm_b_m.allFinite()) n.Fail("lever_arm_b_m", "must be finite");
  c.settle_s = n.NonNegative("settle_s", c.settle_s);
  c.batch_state_interval_s = n.Positive("batch_state_interval_s", c.batch_state_interval_s);
  c.batch_max_iterations = n.Int("batch_max_iterations", c.batch_max_iterations, 1, 100000);
  return c;
}

}  // namespace

TransferConfig LoadTransferConfig(const std::string& path) { return ParseRoot(sim::LoadYamlFile(path)); }

TransferConfig ParseTransferConfig(const std::string& yaml_text, const std::string& file) {
  return ParseRoot(sim::ParseYaml(yaml_text, file));
}

}  // namespace navtwin::transfer
