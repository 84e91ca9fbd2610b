#include "problems/gnss_ins/diagnostics.h"

#include <cstdarg>
#include <cstdio>

#include "core/text.h"
#include "problems/gnss_ins/run.h"

namespace navtwin::gnss_ins {
namespace {

void DiagnoseCounts(const MethodRun& m, std::vector<std::string>* out) {
  if (m.name != "filter") return;  // the smoothers' counts follow rules (thinning), not a gate
  for (const auto& [key, c] : m.solution.counts) {
    if (key == "gnss_reset") {
      if (c.used > 0) {
        out->push_back(StringPrintf("filter: %zu reset(s) of position and velocity to GNSS after rejections in a row "
                                "(its sigma had become too small for its errors)",
                                c.used));
      }
      continue;
    }
    const std::size_t total = c.used + c.rejected;
    if (total > 0 && static_cast<double>(c.rejected) > kWarnRejectedFraction * static_cast<double>(total)) {
      out->push_back(StringPrintf("filter: %s: %zu of %zu rejected by the chi-square gate (%.0f %%)", key.c_str(),
                              c.rejected, total, 100.0 * static_cast<double>(c.rejected) / static_cast<double>(total)));
    }
  }
}

void DiagnoseResiduals(const MethodRun& m, std::vector<std::string>* out) {
  for (const auto& [group, r] : m.solution.residuals) {
    if (r.adapted && (r.sigma_scale > kWarnSigmaScale || r.sigma_scale < 1.0 / kWarnSigmaScale)) {
      out->push_back(StringPrintf("%s: %s: the variance components scale its sigma by %.3g: the configured noise is far "
                              "off, or its errors are not white (time-correlated)",
                              m.name.c_str(), group.c_str(), r.sigma_scale));
    }
    if (!(r.dof >= kWarnMinDof) || !(r.ChiSquarePerDof() > kWarnChiSquarePerDof)) continue;
    out->push_back(StringPrintf("%s: %s: %s %.2f over %.0f dof%s: its noise does not fit its residuals", m.name.c_str(),
                            group.c_str(), m.name == "filter" ? "NIS per dimension" : "chi2/dof",
                            r.ChiSquarePerDof(), r.dof, r.adapted ? " after variance components" : ""));
  }
}

/// The reference's errors against the reported sigma: inside the injected outages when there
/// are any (where the reference is independent of the estimator's input), else everywhere.
void DiagnoseConsistency(const MethodRun& m, std::vector<std::string>* out) {
  if (!m.errors) return;
  static const char* const kNames[kScoredComponents] = {"pos N", "pos E", "pos D", "vel N", "vel E",
                                                        "vel D", "roll",  "pitch", "yaw"};
  const bool outages = !m.errors->outages.empty();
  const ConsistencyStats& c = outages ? m.errors->consistency_inside : m.errors->consistency_all;
  std::string offending;
  for (int k = 0; k < kScoredComponents; ++k) {
    const double ratio = c.RmsRatio(k);
    if (c.count(k) < kWarnMinEpochs || !(ratio > kWarnSigmaRatio || ratio < 1.0 / kWarnSigmaRatio)) continue;
    offending += StringPrintf("%s%s %.2f", offending.empty() ? "" : ", ", kNames[k], ratio);
  }
  if (offending.empty()) return;
  out->push_back(StringPrintf("%s: sigma inconsistent with the reference%s: RMS err/sigma %s (1 when honest; beyond "
                          "%.0f or 1/%.0f)",
                          m.name.c_str(), outages ? " inside the outages" : "", offending.c_str(), kWarnSigmaRatio,
                          kWarnSigmaRatio));
}

}  // namespace

std::vector<std::string> Diagnose(const GnssInsRun& run) {
  std::vector<std::string> out;
  for (const MethodRun& m : run.methods) {
    DiagnoseCounts(m, &out);
    DiagnoseResiduals(m, &out);
    DiagnoseConsistency(m, &out);
  }
  return out;
}

}  // namespace navtwin::gnss_ins
