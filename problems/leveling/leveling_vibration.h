// Leveling under vibration (seed 000, problems/leveling/batch.h): accelerometer samples
// f_meas,k at times t_k (s, relative to a reference such as the window centre) against
// the at-rest specific force plus a bias and H harmonics of a vibration of fundamental f.
// Per sample (3 residuals, body FRD):
//
//   r_k = ( m(roll, pitch) + b + sum_{h=1..H} [ c_h cos(h w_k) + s_h sin(h w_k) ] - f_meas,k ) / sigma
//   m = ( g sin(pitch), -g sin(roll) cos(pitch), -g cos(roll) cos(pitch) )   (equation 1)
//   w_k = 2 pi f t_k
//
// m and its attitude Jacobian are SpecificForceAtRest and SpecificForceAtRestJacobian of
// core/leveling_model.h, the model every leveling method shares (the test also holds the
// whole residual equal to an autodiff reference built on it).
// One cost function holds one sample (the residual of one sample) or a whole window of N
// samples (3N residuals, sample k in rows 3k..3k+2): the window form is the same residuals
// evaluated in one call, which saves the per-block overhead of Ceres and the trigonometry
// of the attitude that all samples share (problems/leveling/batch.cc: 0.13 ms per solve of
// a 120-sample window instead of 0.33 ms with one block per sample).
// Parameter blocks, in this order:
//   attitude [roll_rad, pitch_rad] (2);
//   when H > 0: the fundamental [f_hz] (1), then one block per harmonic h = 1..H
//     [c_x, s_x, c_y, s_y, c_z, s_z] (6, m/s^2);
//   when with_bias: the accelerometer bias b [b_x, b_y, b_z] (3, m/s^2).
// Analytic Jacobian of r_k (rows x, y, z; a = axis):
//   d r / d roll  = (0, -g cos(roll) cos(pitch), g sin(roll) cos(pitch)) / sigma
//   d r / d pitch = (g cos(pitch), g sin(roll) sin(pitch), g cos(roll) sin(pitch)) / sigma
//   d r_a / d f   = 2 pi t_k sum_h h [ -c_{h,a} sin(h w_k) + s_{h,a} cos(h w_k) ] / sigma
//   d r_a / d c_{h,a} = cos(h w_k) / sigma,  d r_a / d s_{h,a} = sin(h w_k) / sigma  (0 across axes)
//   d r / d b     = I / sigma
// cos(h w), sin(h w) come from cos w, sin w by the angle-addition recurrence.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <ceres/cost_function.h>

namespace navtwin::leveling {

class LevelingVibration final : public ceres::CostFunction {
 public:
  static constexpr int kResidualsPerSample = 3;
  static constexpr int kAttitudeSize = 2;   ///< roll_rad, pitch_rad
  static constexpr int kFrequencySize = 1;  ///< f_hz
  static constexpr int kHarmonicSize = 6;   ///< c_x, s_x, c_y, s_y, c_z, s_z (m/s^2)
  static constexpr int kBiasSize = 3;       ///< b (m/s^2)

  /// Samples t_s[k] (relative to the model's time reference), f_meas_b_mps2[k] (at least
  /// one, equal counts); g_mps2 > 0, sigma_mps2 > 0 (1 sigma, each axis), num_harmonics >= 0;
  /// all finite. Throws std::invalid_argument otherwise.
  LevelingVibration(const std::vector<double>& t_s, const std::vector<Eigen::Vector3d>& f_meas_b_mps2,
                    double g_mps2, double sigma_mps2, int num_harmonics, bool with_bias);

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

  /// Index of harmonic h's block (1..H) and of the bias block among the parameter blocks.
  static int HarmonicBlock(int h) { return 1 + h; }
  static int BiasBlock(int num_harmonics) { return num_harmonics > 0 ? 2 + num_harmonics : 1; }

  /// One sample: 3 residuals; block sizes as listed in the header comment.
  static ceres::CostFunction* Create(double t_s, const Eigen::Vector3d& f_meas_b_mps2, double g_mps2,
                                     double sigma_mps2, int num_harmonics, bool with_bias) {
    return new LevelingVibration({t_s}, {f_meas_b_mps2}, g_mps2, sigma_mps2, num_harmonics, with_bias);
  }
  /// A window of samples: 3 N residuals; the same blocks.
  static ceres::CostFunction* Create(const std::vector<double>& t_s, const std::vector<Eigen::Vector3d>& f_meas_b_mps2,
                                     double g_mps2, double sigma_mps2, int num_harmonics, bool with_bias) {
    return new LevelingVibration(t_s, f_meas_b_mps2, g_mps2, sigma_mps2, num_harmonics, with_bias);
  }

 private:
  std::vector<double> two_pi_t_;
  std::vector<Eigen::Vector3d> f_meas_;
  double g_;
  double inv_sigma_;
  int num_harmonics_;
  bool with_bias_;
};

}  // namespace navtwin::leveling
