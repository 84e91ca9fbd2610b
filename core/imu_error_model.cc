#include "core/imu_error_model.h"

#include <stdexcept>

namespace navtwin {

std::string TriadParameterName(const std::string& triad, int index) {
  if (index < 0 || index >= kTriadParameters) {
    throw std::out_of_range("TriadParameterName: index " + std::to_string(index) + " not in [0, 12)");
  }
  if (index < 3) return triad + ".scale_factor." + AxisLetter(index);
  if (index < 9) {
    // Entry k = index - 3 is (row k / 2, col k % 2 skipping the row): MisalignmentIndex inverted.
    const int row = (index - 3) / 2, j = (index - 3) % 2;
    const int col = j < row ? j : j + 1;
    return triad + ".misalignment." + AxisLetter(row) + AxisLetter(col);
  }
  return triad + ".bias." + AxisLetter(index - 9);
}

std::string GSensitivityParameterName(int index) {
  if (index < 0 || index >= kGSensitivityParameters) {
    throw std::out_of_range("GSensitivityParameterName: index " + std::to_string(index) + " not in [0, 9)");
  }
  return std::string("g_sensitivity.") + AxisLetter(index / 3) + AxisLetter(index % 3);
}

}  // namespace navtwin
