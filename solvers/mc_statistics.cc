#include "solvers/mc_statistics.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "solvers/eskf.h"

namespace navtwin::mc {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// e^T P^-1 e, or NaN when P has a non-finite entry or is not positive definite.
double NormalisedErrorSquared(const double* e, const double* p, int d) {
  const Eigen::Map<const Eigen::VectorXd> error(e, d);
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> cov(p, d, d);
  if (!cov.allFinite()) return kNaN;
  const Eigen::LLT<Eigen::MatrixXd> llt(cov);
  if (llt.info() != Eigen::Success) return kNaN;
  return error.dot(llt.solve(error));
}

bool SameAxis(const Quantity& a, const Quantity& b) {
  return a.axis == b.axis && a.components == b.components && a.axis_name == b.axis_name;
}

PointStatistics StatisticsOf(const Quantity& layout, const std::vector<double>& sum_sq,
                             const std::vector<double>& sum_sigma, const std::vector<int>& n_sigma,
                             const std::vector<double>& within, int n, int nees_n, double nees_sum) {
  const int d = layout.dim();
  PointStatistics s;
  s.runs = n;
  for (int i = 0; i < d; ++i) {
    s.rms.push_back(n > 0 ? std::sqrt(sum_sq[i] / n) : kNaN);
    s.sigma_mean.push_back(n_sigma[i] > 0 ? sum_sigma[i] / n_sigma[i] : kNaN);
    s.within_3sigma.push_back(n_sigma[i] > 0 ? within[i] / n_sigma[i] : kNaN);
  }
  s.nees_runs = nees_n;
  s.anees = kNaN;
  s.anees_lo = s.anees_hi = kNaN;
  if (nees_n > 0) {
    const int dof = nees_n * d;
    s.anees = nees_sum / dof;
    s.anees_lo = ChiSquareQuantile(0.025, dof) / dof;
    s.anees_hi = ChiSquareQuantile(0.975, dof) / dof;
  }
  s.bound_sigma.assign(d, kNaN);
  return s;
}

/// The bound's sigma per component at `axis_value` of quantity `name`, when `bound` has it.
void ApplyBound(const MethodRecord& bound, const std::string& name, double axis_value, PointStatistics* s) {
  for (const Quantity& q : bound.quantities) {
    if (q.name != name) continue;
    const int d = q.dim();
    for (int p = 0; p < q.points(); ++p) {
      if (q.axis[p] != axis_value) continue;
      for (int i = 0; i < d && i < static_cast<int>(s->bound_sigma.size()); ++i) s->bound_sigma[i] = q.Sigma(p, i);
      return;
    }
  }
}

}  // namespace

void Accumulator::AddQuantity(const Quantity& q, int runs_before, MethodSums* m) {
  QuantitySums* sums = nullptr;
  for (QuantitySums& s : m->quantities) {
    if (s.layout.name == q.name) sums = &s;
  }
  const int d = q.dim();
  if (sums == nullptr) {
    m->quantities.push_back(QuantitySums());
    sums = &m->quantities.back();
    sums->layout = q;
    sums->layout.error.clear();
    sums->layout.covariance.clear();
    PointSums zero;
    zero.sum_sq.assign(d, 0.0);
    zero.sum_sigma.assign(d, 0.0);
    zero.within.assign(d, 0.0);
    zero.n_sigma.assign(d, 0);
    sums->points.assign(q.points(), zero);
    // Runs before this quantity was first seen had no value for it.
    sums->final_error.assign(static_cast<std::size_t>(runs_before) * d, kNaN);
    sums->final_sigma.assign(static_cast<std::size_t>(runs_before) * d, kNaN);
  } else if (!SameAxis(sums->layout, q)) {
    throw std::logic_error("Monte Carlo: quantity " + q.name + " of " + m->head.method +
                           " has another axis than in the first run");
  }
  for (int p = 0; p < q.points(); ++p) {
    const double* e = &q.error[p * d];
    const double* cov = &q.covariance[p * d * d];
    bool finite = true;
    for (int i = 0; i < d; ++i) finite = finite && std::isfinite(e[i]);
    if (!finite) continue;
    PointSums& ps = sums->points[p];
    ++ps.n;
    for (int i = 0; i < d; ++i) {
      ps.sum_sq[i] += e[i] * e[i];
      const double var = cov[i * d + i];
      if (std::isfinite(var) && var > 0.0) {
        const double sigma = std::sqrt(var);
        ps.sum_sigma[i] += sigma;
        ps.within[i] += std::abs(e[i]) <= 3.0 * sigma ? 1.0 : 0.0;
        ++ps.n_sigma[i];
      }
    }
    const double nees = NormalisedErrorSquared(e, cov, d);
    if (std::isfinite(nees)) {
      ps.nees_sum += nees;
      ++ps.nees_n;
    }
  }
  const int last = q.points() - 1;
  for (int i = 0; i < d; ++i) {
    sums->final_error.push_back(last >= 0 ? q.error[last * d + i] : kNaN);
    sums->final_sigma.push_back(last >= 0 ? q.Sigma(last, i) : kNaN);
  }
}

void Accumulator::Add(const RunRecord& record) {
  for (const MethodRecord& mr : record.methods) {
    MethodSums* m = nullptr;
    for (MethodSums& s : methods_) {
      if (s.head.method == mr.method) m = &s;
    }
    if (m == nullptr) {
      methods_.push_back(MethodSums());
      m = &methods_.back();
      m->head.method = mr.method;
    }
    ++m->head.runs;
    m->head.run_time_s += mr.run_time_s;
    if (!mr.failure.empty() && m->head.failures++ == 0) {
      m->head.first_failure = "seed " + std::to_string(record.seed) + ": " + mr.failure;
    }
    for (const Quantity& q : mr.quantities) AddQuantity(q, runs_, m);
    // A quantity this run lacks (the method failed) gets NaN finals to keep rows aligned.
    for (QuantitySums& s : m->quantities) {
      const std::size_t want = static_cast<std::size_t>(runs_ + 1) * s.layout.dim();
      if (s.final_error.size() < want) {
        s.final_error.resize(want, kNaN);
        s.final_sigma.resize(want, kNaN);
      }
    }
  }
  seeds_.push_back(record.seed);
  ++runs_;
}

std::vector<MethodStatistics> Accumulator::Finish(const MethodRecord* bound) const {
  std::vector<MethodStatistics> out;
  for (const MethodSums& m : methods_) {
    MethodStatistics s = m.head;
    for (const QuantitySums& q : m.quantities) {
      QuantityStatistics qs;
      qs.layout = q.layout;
      for (int p = 0; p < q.layout.points(); ++p) {
        const PointSums& ps = q.points[p];
        qs.points.push_back(StatisticsOf(q.layout, ps.sum_sq, ps.sum_sigma, ps.n_sigma, ps.within, ps.n,
                                         ps.nees_n, ps.nees_sum));
        if (bound != nullptr) ApplyBound(*bound, q.layout.name, q.layout.axis[p], &qs.points.back());
      }
      qs.final_error = q.final_error;
      qs.final_sigma = q.final_sigma;
      const std::size_t want = static_cast<std::size_t>(runs_) * q.layout.dim();
      qs.final_error.resize(want, kNaN);
      qs.final_sigma.resize(want, kNaN);
      s.quantities.push_back(std::move(qs));
    }
    out.push_back(std::move(s));
  }
  return out;
}

int FindMethod(const std::vector<MethodStatistics>& stats, const std::string& name) {
  for (std::size_t i = 0; i < stats.size(); ++i) {
    if (stats[i].method == name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace navtwin::mc
