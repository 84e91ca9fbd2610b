// navtwin convert --in F --out F: reads any supported input and writes the KF-GINS text
// formats (IMU, GNSS, navigation) or the navtwin IMU CSV. The output appears whole or not
// at all.
#include <gflags/gflags.h>

#include <iostream>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/csv_imu.h"
#include "core/io/json_writer.h"
#include "core/io/kfgins.h"
#include "core/io/open.h"

DEFINE_string(in, "", "Input file (any format `navtwin info` knows)");
DEFINE_string(what, "", "Stream to convert: imu, gnss or nav (default: the file's main stream)");
DEFINE_string(to, "", "Output format: kfgins or csv (default: csv for a .csv output, else kfgins)");

namespace navtwin::app {
namespace {

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// The stream a file of this kind is mainly about.
std::string MainStream(FileFormat f) {
  switch (f) {
    case FileFormat::kKfginsGnss:
    case FileFormat::kRtklibPos:
      return "gnss";
    case FileFormat::kKfginsNav:
    case FileFormat::kAnsflGt:
    case FileFormat::kAnsflGtExtended:
      return "nav";
    default:
      return "imu";
  }
}

template <typename Sample, typename Writer>
std::size_t CopyAll(SampleReader<Sample>& reader, Writer& writer) {
  Sample s;
  std::size_t n = 0;
  while (reader.Next(&s)) {
    writer.Write(s);
    ++n;
  }
  writer.Commit();
  return n;
}

int Usage(const std::string& why) {
  std::cerr << "navtwin convert: " << why << "\nusage: " << ConvertCommand().usage << "\n";
  return kExitUsage;
}

int RunConvert(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("unexpected argument '" + args[0] + "'");
  if (FLAGS_in.empty() || FLAGS_out.empty()) return Usage("--in and --out are required");
  if (FLAGS_in == FLAGS_out) return Usage("--in and --out must differ");
  const std::string to = !FLAGS_to.empty() ? FLAGS_to : EndsWith(FLAGS_out, ".csv") ? "csv" : "kfgins";
  if (to != "kfgins" && to != "csv") return Usage("--to must be kfgins or csv");
  const FileFormat in_format = DetectFormat(FLAGS_in);
  const std::string what = FLAGS_what.empty() ? MainStream(in_format) : FLAGS_what;

  std::size_t n = 0;
  if (what == "imu") {
    auto reader = OpenImu(FLAGS_in);
    if (to == "csv") {
      CsvImuWriter writer(FLAGS_out);
      n = CopyAll(*reader, writer);
    } else {
      KfginsImuWriter writer(FLAGS_out);
      n = CopyAll(*reader, writer);
    }
  } else if (what == "gnss" || what == "nav") {
    if (to != "kfgins") return Usage("GNSS and navigation streams are written as kfgins only");
    if (what == "gnss") {
      auto reader = OpenGnss(FLAGS_in);
      KfginsGnssWriter writer(FLAGS_out);
      n = CopyAll(*reader, writer);
    } else {
      auto reader = OpenNav(FLAGS_in);
      KfginsNavWriter writer(FLAGS_out);
      n = CopyAll(*reader, writer);
    }
  } else {
    return Usage("--what must be imu, gnss or nav");
  }
  if (FLAGS_format == "json") {
    JsonWriter w(std::cout);
    w.BeginObject()
        .Field("in", FLAGS_in)
        .Field("in_kind", FormatName(in_format))
        .Field("stream", what)
        .Field("out", FLAGS_out)
        .Field("out_format", to)
        .Field("samples", n)
        .EndObject();
    std::cout << "\n";
  } else {
    std::cout << "converted " << n << " " << what << " samples from " << FLAGS_in << " ("
              << FormatName(in_format) << ") to " << FLAGS_out << " (" << to << ")\n";
  }
  return kExitOk;
}

}  // namespace

Command ConvertCommand() {
  return {"convert", "Convert between formats (ULog, RTKLIB, CSV, drone files -> KF-GINS or CSV)",
          "navtwin convert --in F --out F [--what imu|gnss|nav] [--to kfgins|csv] [--format=json]",
          {"in", "out", "what", "to"},
          &RunConvert};
}

}  // namespace navtwin::app
