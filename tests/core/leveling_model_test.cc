// The leveling measurement model (core/leveling_model.h): equation 1 both ways and its
// Jacobians.
#include "core/leveling_model.h"

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "core/sim/random.h"
#include "core/units.h"

namespace navtwin::leveling {
namespace core_leveling_model_test {


TEST(LevelingModelTest, EquationOneInvertsTheModelInEveryQuadrant) {
  for (double roll_deg : {-170.0, -95.0, -30.0, 0.0, 12.0, 89.0, 135.0}) {
    for (double pitch_deg : {-85.0, -20.0, 0.0, 7.5, 60.0}) {
      const Eigen::Vector3d f = SpecificForceAtRest(roll_deg * kDegToRad, pitch_deg * kDegToRad, kStandardGravity_mps2);
      const RollPitch rp = LevelFromSpecificForce(f);
      // atan2 of exact model values: rounding only.
      EXPECT_NEAR(rp.roll_rad, roll_deg * kDegToRad, 1e-12);
      EXPECT_NEAR(rp.pitch_rad, pitch_deg * kDegToRad, 1e-12);
    }
  }
}

TEST(LevelingModelTest, ModelIsGravityRotatedIntoTheBody) {
  // f_b = R_b_n (0, 0, -g) with R_n_b from roll, pitch (yaw does not matter).
  const double roll = 0.3, pitch = -0.2;
  const Eigen::Matrix3d r_n_b = DcmFromEuler(roll, pitch, 1.1);
  const Eigen::Vector3d expected = r_n_b.transpose() * Eigen::Vector3d(0.0, 0.0, -kStandardGravity_mps2);
  EXPECT_NEAR((SpecificForceAtRest(roll, pitch, kStandardGravity_mps2) - expected).norm(), 0.0, 1e-12);
}

TEST(LevelingModelTest, LevelJacobianMatchesCentralDifferences) {
  sim::Rng rng(21);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d f = SpecificForceAtRest(rng.Uniform(-1.5, 1.5), rng.Uniform(-1.4, 1.4), kStandardGravity_mps2) +
                              rng.Normal3(0.5);
    const Eigen::Matrix<double, 2, 3> j = LevelJacobian(f);
    const double h = 1e-6;
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d fp = f, fm = f;
      fp[c] += h;
      fm[c] -= h;
      const RollPitch p = LevelFromSpecificForce(fp), m = LevelFromSpecificForce(fm);
      // Central differences of a smooth function at h = 1e-6 m/s^2: error ~1e-10 relative.
      EXPECT_NEAR(j(0, c), (p.roll_rad - m.roll_rad) / (2 * h), 1e-8);
      EXPECT_NEAR(j(1, c), (p.pitch_rad - m.pitch_rad) / (2 * h), 1e-8);
    }
  }
}

TEST(LevelingModelTest, SpecificForceJacobianMatchesCentralDifferences) {
  sim::Rng rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const double roll = rng.Uniform(-3.0, 3.0), pitch = rng.Uniform(-1.5, 1.5), g = rng.Uniform(9.0, 10.5);
    const Eigen::Matrix<double, 3, 2> j = SpecificForceAtRestJacobian(roll, pitch, g);
    const double h = 1e-6;
    const Eigen::Vector3d d_roll =
        (SpecificForceAtRest(roll + h, pitch, g) - SpecificForceAtRest(roll - h, pitch, g)) / (2 * h);
    const Eigen::Vector3d d_pitch =
        (SpecificForceAtRest(roll, pitch + h, g) - SpecificForceAtRest(roll, pitch - h, g)) / (2 * h);
    // Central differences at h = 1e-6 rad of a function of size g: error ~1e-9 m/s^2.
    EXPECT_NEAR((j.col(0) - d_roll).norm(), 0.0, 1e-7);
    EXPECT_NEAR((j.col(1) - d_pitch).norm(), 0.0, 1e-7);
  }
}

}  // namespace core_leveling_model_test
}  // namespace navtwin::leveling
