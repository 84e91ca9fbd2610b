#include "problems/calibration/calibration_run_folder.h"

#include <cstdio>
#include <memory>

#include "core/io/atomic_file.h"
#include "core/io/folder.h"

namespace navtwin::calibration {

void WriteCalibrationRunFolder(const std::string& dir, const std::string& summary_json, const CalibrationFile& file,
                               const std::vector<RunFolderFile>& files) {
  EnsureFolder(dir);
  std::vector<std::unique_ptr<AtomicFile>> pending;
  pending.push_back(std::make_unique<AtomicFile>(dir + "/summary.json"));
  pending.back()->stream() << summary_json << "\n";
  for (const RunFolderFile& f : files) {
    pending.push_back(std::make_unique<AtomicFile>(dir + "/" + f.first));
    f.second(pending.back()->stream());
  }
  const std::string calibration_path = dir + "/calibration.yaml";
  WriteCalibrationFile(calibration_path, file);
  try {
    for (auto& p : pending) p->Commit();
  } catch (...) {
    for (auto& p : pending) p->Revoke();
    std::remove(calibration_path.c_str());
    throw;
  }
}

}  // namespace navtwin::calibration
