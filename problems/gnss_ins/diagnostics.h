// What went wrong in a GNSS/INS run, in sentences a person reads: measurements the filter's
// gate rejected, resets to GNSS, residual groups whose noise does not fit, and standard
// deviations that the reference shows to be wrong. The run prints them on stderr, lists
// them under the table and in summary.json ("warnings"); `--strict` turns them into a
// failing exit code.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace navtwin::gnss_ins {

struct GnssInsRun;

/// A measurement kind whose share of rejected samples exceeds this is reported (the filter's
/// chi-square gate at its default probability rejects 1e-4 of consistent measurements).
constexpr double kWarnRejectedFraction = 0.10;
/// A residual group whose chi-square per degree of freedom exceeds this is reported (for
/// 10 dof, chi2 / dof > 3 has a probability of 5e-4 when the noise fits).
constexpr double kWarnChiSquarePerDof = 3.0;
/// Residual groups with fewer degrees of freedom are not judged.
constexpr double kWarnMinDof = 10.0;
/// Nor is err/sigma over fewer compared reference epochs.
constexpr std::size_t kWarnMinEpochs = 10;
/// The reference's errors against the reported sigma: an RMS of err / sigma beyond this
/// factor either way means the sigmas are wrong (and the smoothed solution not a reference).
constexpr double kWarnSigmaRatio = 3.0;

/// A variance component that scales a group's sigma by more than this factor (or less than
/// its inverse) is reported: the configured noise was far off, or the group's errors are not
/// white (time-correlated GNSS errors under a noisy IMU drive the estimate towards zero).
constexpr double kWarnSigmaScale = 10.0;

/// The warnings of a finished run, one sentence each, prefixed by the method.
std::vector<std::string> Diagnose(const GnssInsRun& run);

}  // namespace navtwin::gnss_ins
