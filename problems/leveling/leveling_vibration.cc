#include "problems/leveling/leveling_vibration.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/leveling_model.h"

namespace navtwin::leveling {

LevelingVibration::LevelingVibration(const std::vector<double>& t_s, const std::vector<Eigen::Vector3d>& f_meas_b_mps2,
                                     double g_mps2, double sigma_mps2, int num_harmonics, bool with_bias)
    : f_meas_(f_meas_b_mps2), g_(g_mps2), inv_sigma_(1.0 / sigma_mps2), num_harmonics_(num_harmonics),
      with_bias_(with_bias) {
  if (t_s.empty() || t_s.size() != f_meas_b_mps2.size()) {
    throw std::invalid_argument("LevelingVibration: need at least one sample and one time per sample");
  }
  const bool finite = std::all_of(t_s.begin(), t_s.end(), [](double t) { return std::isfinite(t); }) &&
                      std::all_of(f_meas_b_mps2.begin(), f_meas_b_mps2.end(),
                                  [](const Eigen::Vector3d& f) { return f.allFinite(); });
  if (!finite) throw std::invalid_argument("LevelingVibration: t_s and f_meas_b_mps2 must be finite");
  if (!(g_mps2 > 0.0) || !std::isfinite(g_mps2) || !(sigma_mps2 > 0.0) || !std::isfinite(sigma_mps2)) {
    throw std::invalid_argument("LevelingVibration: g_mps2 and sigma_mps2 must be positive and finite");
  }
  if (num_harmonics < 0) throw std::invalid_argument("LevelingVibration: num_harmonics must be >= 0");
  two_pi_t_.reserve(t_s.size());
  for (const double t : t_s) two_pi_t_.push_back(2.0 * M_PI * t);
  set_num_residuals(kResidualsPerSample * static_cast<int>(t_s.size()));
  std::vector<int32_t>* sizes = mutable_parameter_block_sizes();
  sizes->push_back(kAttitudeSize);
  if (num_harmonics > 0) {
    sizes->push_back(kFrequencySize);
    sizes->insert(sizes->end(), num_harmonics, kHarmonicSize);
  }
  if (with_bias) sizes->push_back(kBiasSize);
}

bool LevelingVibration::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  // Shared by every sample: the at-rest model, its Jacobian and the bias.
  const Eigen::Vector3d at_rest = leveling::SpecificForceAtRest(parameters[0][0], parameters[0][1], g_);
  // d r / d (roll, pitch), 3 x 2 row-major: rows x, y, z; columns roll, pitch.
  const Eigen::Matrix<double, 3, 2, Eigen::RowMajor> j_attitude =
      leveling::SpecificForceAtRestJacobian(parameters[0][0], parameters[0][1], g_) * inv_sigma_;
  const int bias_block = BiasBlock(num_harmonics_);
  const Eigen::Vector3d bias =
      with_bias_ ? Eigen::Vector3d(Eigen::Map<const Eigen::Vector3d>(parameters[bias_block])) : Eigen::Vector3d::Zero();
  const auto wanted = [jacobians](int block) { return jacobians != nullptr && jacobians[block] != nullptr; };

  const int n = static_cast<int>(f_meas_.size());
  for (int k = 0; k < n; ++k) {
    Eigen::Vector3d e = at_rest + bias - f_meas_[k];
    if (num_harmonics_ > 0) {
      const double w = two_pi_t_[k] * parameters[1][0];
      const double c1 = std::cos(w), s1 = std::sin(w);
      double ch = c1, sh = s1;  // cos(h w), sin(h w)
      Eigen::Vector3d de_dw = Eigen::Vector3d::Zero();
      for (int h = 1; h <= num_harmonics_; ++h) {
        const double* q = parameters[HarmonicBlock(h)];
        for (int a = 0; a < 3; ++a) {
          e[a] += q[2 * a] * ch + q[2 * a + 1] * sh;
          de_dw[a] += h * (q[2 * a + 1] * ch - q[2 * a] * sh);
        }
        if (wanted(HarmonicBlock(h))) {
          double* j = jacobians[HarmonicBlock(h)] + 3 * k * kHarmonicSize;  // 3 x 6 row-major
          std::fill(j, j + 3 * kHarmonicSize, 0.0);
          for (int a = 0; a < 3; ++a) {
            j[a * kHarmonicSize + 2 * a] = ch * inv_sigma_;
            j[a * kHarmonicSize + 2 * a + 1] = sh * inv_sigma_;
          }
        }
        const double next_c = ch * c1 - sh * s1;
        sh = sh * c1 + ch * s1;
        ch = next_c;
      }
      if (wanted(1)) {
        for (int a = 0; a < 3; ++a) jacobians[1][3 * k + a] = two_pi_t_[k] * de_dw[a] * inv_sigma_;
      }
    }
    if (wanted(0)) std::copy(j_attitude.data(), j_attitude.data() + 6, jacobians[0] + 3 * k * kAttitudeSize);
    if (with_bias_ && wanted(bias_block)) {
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> j(jacobians[bias_block] + 3 * k * kBiasSize);
      j = Eigen::Matrix3d::Identity() * inv_sigma_;
    }
    for (int a = 0; a < 3; ++a) residuals[3 * k + a] = e[a] * inv_sigma_;
  }
  return true;
}

}  // namespace navtwin::leveling
