// WriteTransferRunFolder (run.h): the run folder of `transfer-align --out DIR`.
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/io/atomic_file.h"
#include "core/io/folder.h"
#include "problems/transfer_alignment/run.h"

namespace navtwin::transfer {
namespace {

/// A number as the run folders write them: shortest round-trip form, "nan" for NaN.
std::string CsvNumber(double x) {
  if (x != x) return "nan";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);
  return buffer;
}

void WriteEstimates(const TransferResult& r, AtomicFile* file) {
  std::ostream& o = file->stream();
  o << "t_s,mis_roll_deg,mis_pitch_deg,mis_yaw_deg,mis_roll_std_mrad,mis_pitch_std_mrad,mis_yaw_std_mrad,delay_s,"
       "delay_std_s\n";
  for (const TransferResult::Estimate& e : r.estimates) {
    o << CsvNumber(e.t_s);
    for (int k = 0; k < 3; ++k) o << ',' << CsvNumber(e.misalignment_deg[k]);
    for (int k = 0; k < 3; ++k) o << ',' << CsvNumber(e.misalignment_sigma_mrad[k]);
    o << ',' << CsvNumber(e.delay_s) << ',' << CsvNumber(e.delay_sigma_s) << '\n';
  }
}

void WriteAttitudeErrors(const TransferResult& r, AtomicFile* file) {
  std::ostream& o = file->stream();
  o << "t_s,roll_err_mrad,pitch_err_mrad,heading_err_mrad\n";
  for (std::size_t i = 0; i < r.t_s.size(); ++i) {
    o << CsvNumber(r.t_s[i]);
    for (int k = 0; k < 3; ++k) o << ',' << CsvNumber(r.error_mrad[i][k]);
    o << '\n';
  }
}

}  // namespace

void WriteTransferRunFolder(const std::string& dir, const std::vector<TransferResult>& results) {
  EnsureFolder(dir);
  std::vector<std::unique_ptr<AtomicFile>> files;
  for (const TransferResult& r : results) {
    const std::string method_dir = dir + "/" + MethodName(r.method);
    EnsureFolder(method_dir);
    files.push_back(std::make_unique<AtomicFile>(method_dir + "/estimates.csv"));
    WriteEstimates(r, files.back().get());
    if (!r.t_s.empty()) {
      files.push_back(std::make_unique<AtomicFile>(method_dir + "/attitude_errors.csv"));
      WriteAttitudeErrors(r, files.back().get());
    }
  }
  files.push_back(std::make_unique<AtomicFile>(dir + "/summary.json"));
  std::ostream& summary = files.back()->stream();
  summary << "{\"command\":\"transfer-align\",\"methods\":{";
  for (std::size_t i = 0; i < results.size(); ++i) {
    summary << (i ? "," : "") << '"' << MethodName(results[i].method) << "\":" << TransferResultJson(results[i]);
  }
  summary << "}}\n";
  for (const auto& f : files) f->Commit();
}

}  // namespace navtwin::transfer
