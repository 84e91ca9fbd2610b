#include "problems/gnss_ins/diagnostics.h"

#include <cstdarg>
#include <cstdio>

#include "problems/gnss_ins/run.h"

namespace navtwin::gnss_ins {
namespace {

std::string Sentence(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string Sentence(const char* format, ...) {
  char buf[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buf, sizeof buf, format, args);
  va_end(args);
  return buf;
}

void DiagnoseCounts(const MethodRun& m, std::vector<std::string>* out) {
  if (m.name != "filter") return;  // the smoothers' counts follow rules (thinning), not a gate
  for (const auto& [key, c] : m.solution.counts) {
    if (key == "gnss_reset") {
      if (c.used > 0) {
        out->push_back(Sentence("filter: %zu reset(s) of position and velocity to GNSS after rejections in a row "
                                "(its sigma had become too small for its errors)",
                                c.used));
      }
      continue;
    }
    const std::size_t total = c.used + c.rejected;
    if (total > 0 && static_cast<double>(c.rejected) > kWarnRejectedFraction * static_cast<double>(total)) {
      out->push_back(Sentence("filter: %s: %zu of %zu rejected by the chi-square gate (%.0f %%)", key.c_str(),
                              c.rejected, total, 100.0 * static_cast<double>(c.rejected) / static_cast<double>(total)));
    }
  }
}

void DiagnoseResiduals(const MethodRun& m, std::vector<std::string>* out) {
  for (const auto& [group, r] : m.solution.residuals) {
    if (!(r.dof >= kWarnMinDof) || !(r.ChiSquarePerDof() > kWarnChiSquarePerDof)) continue;
    out->push_back(Sentence("%s: %s: %s %.2f over %.0f dof%s: its noise does not fit its residuals", m.name.c_str(),
                            group.c_str(), m.name == "filter" ? "NIS per dimension" : "chi2/dof",
                            r.ChiSquarePerDof(), r.dof, r.adapted ? " after variance components" : ""));
  }
}

}  // namespace

std::vector<std::string> Diagnose(const GnssInsRun& run) {
  std::vector<std::string> out;
  for (const MethodRun& m : run.methods) {
    DiagnoseCounts(m, &out);
    DiagnoseResiduals(m, &out);
  }
  return out;
}

}  // namespace navtwin::gnss_ins
