// LevelingVibration: layout of the parameter blocks, the residual against a templated
// reference built on the shared leveling model (core/leveling_model.h), and every
// analytic Jacobian block against autodiff of that reference and against central
// differences, at zero, at a tiny perturbation and at a random point (fixed seed), for one
// sample and for a window of samples; the window form is the samples stacked.
#include "problems/leveling/leveling_vibration.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <ceres/dynamic_autodiff_cost_function.h>
#include <gtest/gtest.h>

#include "core/leveling_model.h"
#include "core/units.h"

namespace navtwin::leveling {
namespace leveling_leveling_vibration_test {

constexpr double kSigma = 0.49;  // 50 mg

// The residuals of the header comment written with the shared model and plain cos/sin of
// each harmonic (no recurrence), for autodiff: sample k in rows 3k..3k+2.
struct Reference {
  std::vector<double> t_s;
  std::vector<Eigen::Vector3d> f_meas;
  int num_harmonics;
  bool with_bias;

  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    using std::cos;
    using std::sin;
    for (size_t k = 0; k < t_s.size(); ++k) {
      Eigen::Matrix<T, 3, 1> e = leveling::SpecificForceAtRest(p[0][0], p[0][1], T(kStandardGravity_mps2)) - f_meas[k].cast<T>();
      for (int h = 1; h <= num_harmonics; ++h) {
        const T w = T(2.0 * M_PI * h * t_s[k]) * p[1][0];
        for (int a = 0; a < 3; ++a) e[a] += p[1 + h][2 * a] * cos(w) + p[1 + h][2 * a + 1] * sin(w);
      }
      if (with_bias) {
        for (int a = 0; a < 3; ++a) e[a] += p[LevelingVibration::BiasBlock(num_harmonics)][a];
      }
      for (int a = 0; a < 3; ++a) r[3 * k + a] = e[a] / T(kSigma);
    }
    return true;
  }
};

std::unique_ptr<ceres::CostFunction> ReferenceCost(const Reference& ref) {
  auto cost = std::make_unique<ceres::DynamicAutoDiffCostFunction<Reference, 4>>(new Reference(ref));
  cost->AddParameterBlock(LevelingVibration::kAttitudeSize);
  if (ref.num_harmonics > 0) cost->AddParameterBlock(LevelingVibration::kFrequencySize);
  for (int h = 1; h <= ref.num_harmonics; ++h) cost->AddParameterBlock(LevelingVibration::kHarmonicSize);
  if (ref.with_bias) cost->AddParameterBlock(LevelingVibration::kBiasSize);
  cost->SetNumResiduals(3 * static_cast<int>(ref.t_s.size()));
  return cost;
}

using Blocks = std::vector<std::vector<double>>;
using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct Evaluation {
  Eigen::VectorXd residual;
  std::vector<RowMajor> jacobians;
};

Evaluation Evaluate(const ceres::CostFunction& f, const Blocks& blocks, bool with_jacobians) {
  std::vector<const double*> params;
  for (const auto& b : blocks) params.push_back(b.data());
  Evaluation out;
  out.residual.resize(f.num_residuals());
  std::vector<double*> ptrs;
  for (const auto& b : blocks) {
    out.jacobians.emplace_back(RowMajor::Constant(f.num_residuals(), static_cast<int>(b.size()), std::nan("")));
    ptrs.push_back(out.jacobians.back().data());
  }
  EXPECT_TRUE(f.Evaluate(params.data(), out.residual.data(), with_jacobians ? ptrs.data() : nullptr));
  return out;
}

RowMajor CentralDifferences(const ceres::CostFunction& f, const Blocks& blocks, int k) {
  // Step 1e-6 in every coordinate (rad, Hz, m/s^2): truncation ~h^2 |r'''| < 1e-9 and
  // rounding ~eps |r| / h ~ 1e-8 for residuals of up to ~100.
  constexpr double kStep = 1e-6;
  RowMajor j(f.num_residuals(), static_cast<int>(blocks[k].size()));
  for (int i = 0; i < j.cols(); ++i) {
    Blocks plus = blocks, minus = blocks;
    plus[k][i] += kStep;
    minus[k][i] -= kStep;
    j.col(i) = (Evaluate(f, plus, false).residual - Evaluate(f, minus, false).residual) / (2.0 * kStep);
  }
  return j;
}

struct Point {
  std::string name;
  std::vector<double> t_s;
  std::vector<Eigen::Vector3d> f_meas;
  Blocks blocks;  // attitude, [f, harmonics], [bias]
};

Blocks MakeBlocks(int num_harmonics, bool with_bias, const std::function<double()>& value, double f_hz) {
  Blocks blocks{{value(), value()}};
  if (num_harmonics > 0) blocks.push_back({f_hz});
  for (int h = 1; h <= num_harmonics; ++h) {
    blocks.emplace_back(6);
    for (double& v : blocks.back()) v = 5.0 * value();
  }
  if (with_bias) blocks.push_back({value(), value(), value()});
  return blocks;
}

// Zero, a tiny perturbation and a random point for one sample, and a random window of
// five samples. Random: |roll|, |pitch| < 1.5 rad, f in 10..40 Hz, tones up to 5 m/s^2,
// bias up to 1.5 m/s^2, t within 0.1 s of the reference (a 0.2 s window).
std::vector<Point> Points(int num_harmonics, bool with_bias) {
  std::mt19937 rng(20250117);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random = [&] { return 1.5 * u(rng); };
  const Eigen::Vector3d f_meas(1.2, -0.7, -9.9);
  std::vector<Point> points;
  points.push_back({"zero", {0.0}, {f_meas}, MakeBlocks(num_harmonics, with_bias, [] { return 0.0; }, 0.0)});
  points.push_back({"tiny", {1e-9}, {f_meas}, MakeBlocks(num_harmonics, with_bias, [&] { return 1e-9 * u(rng); }, 1e-9)});
  const double t = 0.1 * u(rng);
  points.push_back({"random", {t}, {f_meas}, MakeBlocks(num_harmonics, with_bias, random, 25.0 + 15.0 * u(rng))});
  Point window{"window", {}, {}, MakeBlocks(num_harmonics, with_bias, random, 25.0 + 15.0 * u(rng))};
  for (int k = 0; k < 5; ++k) {
    window.t_s.push_back(0.1 * u(rng));
    window.f_meas.push_back(f_meas + Eigen::Vector3d(u(rng), u(rng), u(rng)));
  }
  points.push_back(window);
  return points;
}

std::unique_ptr<ceres::CostFunction> Create(const Point& p, int num_harmonics, bool with_bias) {
  if (p.t_s.size() == 1) {
    return std::unique_ptr<ceres::CostFunction>(
        LevelingVibration::Create(p.t_s[0], p.f_meas[0], kStandardGravity_mps2, kSigma, num_harmonics, with_bias));
  }
  return std::unique_ptr<ceres::CostFunction>(
      LevelingVibration::Create(p.t_s, p.f_meas, kStandardGravity_mps2, kSigma, num_harmonics, with_bias));
}

struct Layout {
  int num_harmonics;
  bool with_bias;
};

class LevelingVibrationLayouts : public ::testing::TestWithParam<Layout> {};

TEST_P(LevelingVibrationLayouts, JacobiansMatchAutodiffAndCentralDifferences) {
  const Layout layout = GetParam();
  for (const Point& p : Points(layout.num_harmonics, layout.with_bias)) {
    SCOPED_TRACE(p.name);
    const std::unique_ptr<ceres::CostFunction> f = Create(p, layout.num_harmonics, layout.with_bias);
    const std::unique_ptr<ceres::CostFunction> ref =
        ReferenceCost({p.t_s, p.f_meas, layout.num_harmonics, layout.with_bias});
    ASSERT_EQ(f->num_residuals(), 3 * static_cast<int>(p.t_s.size()));
    ASSERT_EQ(f->parameter_block_sizes(), ref->parameter_block_sizes());
    ASSERT_EQ(f->parameter_block_sizes().size(), p.blocks.size());
    const Evaluation analytic = Evaluate(*f, p.blocks, true);
    const Evaluation autodiff = Evaluate(*ref, p.blocks, true);
    // The same function evaluated two ways (recurrence vs direct cos/sin of h w): rounding.
    EXPECT_LE((analytic.residual - autodiff.residual).norm(), 1e-12 * (1.0 + autodiff.residual.norm()));
    // Residual without Jacobians: identical code path for the value.
    EXPECT_EQ(Evaluate(*f, p.blocks, false).residual, analytic.residual);
    for (size_t k = 0; k < p.blocks.size(); ++k) {
      SCOPED_TRACE("block " + std::to_string(k));
      const double scale = std::max(1.0, autodiff.jacobians[k].cwiseAbs().maxCoeff());
      // Autodiff is exact up to rounding of the same operations.
      EXPECT_LE((analytic.jacobians[k] - autodiff.jacobians[k]).cwiseAbs().maxCoeff(), 1e-12 * scale)
          << "analytic\n" << analytic.jacobians[k] << "\nautodiff\n" << autodiff.jacobians[k];
      // Central differences with the step of CentralDifferences: 1e-7 relative.
      EXPECT_LE((analytic.jacobians[k] - CentralDifferences(*f, p.blocks, static_cast<int>(k))).cwiseAbs().maxCoeff(),
                1e-7 * scale);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Layouts, LevelingVibrationLayouts,
                         ::testing::Values(Layout{0, false}, Layout{0, true}, Layout{1, false}, Layout{1, true},
                                           Layout{2, false}, Layout{3, true}),
                         [](const ::testing::TestParamInfo<Layout>& info) {
                           return "H" + std::to_string(info.param.num_harmonics) +
                                  (info.param.with_bias ? "_bias" : "_nobias");
                         });

TEST(LevelingVibrationTest, LayoutAndBlockIndices) {
  const std::unique_ptr<ceres::CostFunction> f(LevelingVibration::Create(0.01, Eigen::Vector3d::Zero(), kStandardGravity_mps2, 1.0, 2, true));
  EXPECT_EQ(f->num_residuals(), 3);
  EXPECT_EQ(f->parameter_block_sizes(), (std::vector<int32_t>{2, 1, 6, 6, 3}));
  EXPECT_EQ(LevelingVibration::HarmonicBlock(1), 2);
  EXPECT_EQ(LevelingVibration::BiasBlock(2), 4);
  EXPECT_EQ(LevelingVibration::BiasBlock(0), 1);
  const std::unique_ptr<ceres::CostFunction> plain(LevelingVibration::Create(0.0, Eigen::Vector3d::Zero(), kStandardGravity_mps2, 1.0, 0, false));
  EXPECT_EQ(plain->parameter_block_sizes(), (std::vector<int32_t>{2}));
}

TEST(LevelingVibrationTest, WindowIsTheSamplesStacked) {
  const Point p = Points(2, true).back();
  const std::unique_ptr<ceres::CostFunction> window = Create(p, 2, true);
  const Evaluation all = Evaluate(*window, p.blocks, true);
  for (size_t k = 0; k < p.t_s.size(); ++k) {
    const std::unique_ptr<ceres::CostFunction> one(LevelingVibration::Create(p.t_s[k], p.f_meas[k], kStandardGravity_mps2, kSigma, 2, true));
    const Evaluation e = Evaluate(*one, p.blocks, true);
    // The same operations on the same values: equal to the last bit.
    EXPECT_EQ(all.residual.segment<3>(3 * k), e.residual);
    for (size_t b = 0; b < p.blocks.size(); ++b) EXPECT_EQ(all.jacobians[b].middleRows(3 * k, 3), e.jacobians[b]);
  }
}

TEST(LevelingVibrationTest, ValueOfAToneAtAKnownTime) {
  // Level, no bias, one tone on x with c = 0, s = 2 at f = 25 Hz, t = 0.01 s: the tone is
  // 2 sin(pi / 2) = 2; the measurement equals the model except 1 m/s^2 less on x, so the
  // residual is (1, 0, 0) / sigma.
  const std::unique_ptr<ceres::CostFunction> f(
      LevelingVibration::Create(0.01, Eigen::Vector3d(1.0, 0.0, -kStandardGravity_mps2), kStandardGravity_mps2, 0.5, 1, false));
  const Evaluation e = Evaluate(*f, {{0.0, 0.0}, {25.0}, {0.0, 2.0, 0.0, 0.0, 0.0, 0.0}}, false);
  // sin(pi/2) and cos(pi/2) in floating point: 1e-15.
  EXPECT_NEAR(e.residual.x(), 2.0, 1e-12);
  EXPECT_NEAR(e.residual.y(), 0.0, 1e-12);
  EXPECT_NEAR(e.residual.z(), 0.0, 1e-12);
}

TEST(LevelingVibrationTest, NullJacobianBlocksAreSkipped) {
  // Ceres passes nullptr for constant blocks: the others are still filled correctly.
  const std::unique_ptr<ceres::CostFunction> f(LevelingVibration::Create(0.03, Eigen::Vector3d(0.5, 0.2, -9.7), kStandardGravity_mps2, kSigma, 1, true));
  const Blocks blocks{{0.1, -0.2}, {23.3}, {1.0, 2.0, 0.5, -0.5, 0.0, 0.1}, {0.01, 0.02, 0.03}};
  const Evaluation full = Evaluate(*f, blocks, true);
  std::vector<const double*> params;
  for (const auto& b : blocks) params.push_back(b.data());
  RowMajor j_att(3, 2), j_bias(3, 3);
  double* jacobians[] = {j_att.data(), nullptr, nullptr, j_bias.data()};
  Eigen::Vector3d r;
  ASSERT_TRUE(f->Evaluate(params.data(), r.data(), jacobians));
  EXPECT_EQ(r, full.residual);
  EXPECT_EQ(j_att, full.jacobians[0]);
  EXPECT_EQ(j_bias, full.jacobians[3]);
}

TEST(LevelingVibrationTest, RejectsInvalidArguments) {
  const Eigen::Vector3d f(0.0, 0.0, -kStandardGravity_mps2);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  using V = std::vector<Eigen::Vector3d>;
  EXPECT_THROW(LevelingVibration({0.0}, V{f}, kStandardGravity_mps2, 0.0, 1, false), std::invalid_argument);
  EXPECT_THROW(LevelingVibration({0.0}, V{f}, -1.0, 1.0, 1, false), std::invalid_argument);
  EXPECT_THROW(LevelingVibration({nan}, V{f}, kStandardGravity_mps2, 1.0, 1, false), std::invalid_argument);
  EXPECT_THROW(LevelingVibration({0.0}, V{Eigen::Vector3d(nan, 0.0, 0.0)}, kStandardGravity_mps2, 1.0, 1, false), std::invalid_argument);
  EXPECT_THROW(LevelingVibration({0.0}, V{f}, kStandardGravity_mps2, 1.0, -1, false), std::invalid_argument);
  EXPECT_THROW(LevelingVibration({}, V{}, kStandardGravity_mps2, 1.0, 1, false), std::invalid_argument);
  EXPECT_THROW(LevelingVibration({0.0, 0.1}, V{f}, kStandardGravity_mps2, 1.0, 1, false), std::invalid_argument);
}

}  // namespace leveling_leveling_vibration_test
}  // namespace navtwin::leveling
