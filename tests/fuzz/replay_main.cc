// Replays a fuzz target's inputs without libFuzzer (any compiler): calls the target's
// LLVMFuzzerTestOneInput on every file of the corpus folder and of the regressions folder.
//   fuzz_replay_<target> <corpus folder> <regressions folder> [--data=FILE[+TAG]...]
// --data seeds come from the real records (never copied into the repository): the first
// 8 KB of $NAVTWIN_DATA/FILE (else the configured ../shared/data), cut at a line end, with
// the whole of TAG appended when given (rtklib-walk's tag file); of a binary ULog (.ulg) the
// first 64 KB as they are (past the definitions to the first data messages). A missing data
// file fails the replay when CI is set, else it is skipped. Fails when no input was
// replayed at all (a replay of nothing would pass unseen), unless only skipped data seeds
// were given: then exit code 77, which ctest reports as skipped. A missing corpus or
// regressions folder is an empty one. A crash or an unexpected exception in the
// target ends the program abnormally, which is the finding.
#include <algorithm>
#include <cstddef>
#include <limits>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace replay_main {

std::vector<std::filesystem::path> InputsIn(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> inputs;
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error)) return inputs;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.is_regular_file()) inputs.push_back(entry.path());
  }
  std::sort(inputs.begin(), inputs.end());
  return inputs;
}

/// The file's bytes, at most max_bytes of them (the data logs are megabytes; a seed is their head).
std::vector<std::uint8_t> Bytes(const std::filesystem::path& file,
                                std::size_t max_bytes = std::numeric_limits<std::size_t>::max()) {
  std::ifstream in(file, std::ios::binary);
  std::vector<std::uint8_t> bytes;
  char chunk[4096];
  while (bytes.size() < max_bytes && in.read(chunk, sizeof chunk).gcount() > 0) {
    const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(in.gcount()), max_bytes - bytes.size());
    bytes.insert(bytes.end(), chunk, chunk + n);
  }
  return bytes;
}

constexpr std::size_t kDataHead = 8192;
constexpr std::size_t kBinaryHead = 65536;
constexpr int kSkipped = 77;

std::filesystem::path DataDir() {
  const char* env = std::getenv("NAVTWIN_DATA");
  return env != nullptr && *env != '\0' ? env : NAVTWIN_DEFAULT_DATA_DIR;
}

/// One --data seed: FILE's head (and TAG whole); false when a file is missing.
bool DataSeed(const std::string& spec, std::vector<std::uint8_t>* bytes) {
  const std::size_t plus = spec.find('+');
  const std::filesystem::path file = DataDir() / spec.substr(0, plus);
  if (!std::filesystem::is_regular_file(file)) return false;
  const bool binary = file.extension() == ".ulg";
  const std::size_t head = binary ? kBinaryHead : kDataHead;
  *bytes = Bytes(file, head + 1);
  if (bytes->size() > head) {
    bytes->resize(head);
    while (!binary && !bytes->empty() && bytes->back() != '\n') bytes->pop_back();
  }
  if (plus == std::string::npos) return true;
  const std::filesystem::path tag = DataDir() / spec.substr(plus + 1);
  if (!std::filesystem::is_regular_file(tag)) return false;
  const std::vector<std::uint8_t> tail = Bytes(tag);
  bytes->insert(bytes->end(), tail.begin(), tail.end());
  return true;
}

/// The --data seeds; -1 when one is missing under CI. *skipped: those missing otherwise.
long ReplayData(const std::vector<std::string>& specs, std::size_t* skipped) {
  long count = 0;
  for (const std::string& spec : specs) {
    std::vector<std::uint8_t> bytes;
    if (!DataSeed(spec, &bytes)) {
      std::fprintf(stderr, "data seed %s not found under %s%s\n", spec.c_str(), DataDir().string().c_str(),
                   std::getenv("CI") != nullptr ? "" : " (skipped)");
      if (std::getenv("CI") != nullptr) return -1;
      ++*skipped;
      continue;
    }
    std::printf("replay data %s\n", spec.c_str());
    std::fflush(stdout);
    LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
    ++count;
  }
  return count;
}

std::size_t Replay(const std::vector<std::filesystem::path>& inputs) {
  for (const auto& input : inputs) {
    std::printf("replay %s\n", input.string().c_str());
    std::fflush(stdout);  // the last line names the input when the target crashes
    const std::vector<std::uint8_t> bytes = Bytes(input);
    LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
  }
  return inputs.size();
}

}  // namespace replay_main

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s <corpus folder> <regressions folder> [--data=FILE[+TAG]...]\n", argv[0]);
    return 2;
  }
  std::vector<std::string> data;
  for (int i = 3; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--data=", 0) != 0) {
      std::fprintf(stderr, "unexpected argument %s\n", argv[i]);
      return 2;
    }
    data.push_back(arg.substr(7));
  }
  const std::size_t corpus = replay_main::Replay(replay_main::InputsIn(argv[1]));
  const std::size_t regressions = replay_main::Replay(replay_main::InputsIn(argv[2]));
  std::size_t skipped = 0;
  const long seeds = replay_main::ReplayData(data, &skipped);
  if (seeds < 0) return 1;
  if (corpus + static_cast<std::size_t>(seeds) == 0 && skipped > 0) {
    std::fprintf(stderr, "only data seeds, all missing: skipped\n");
    return replay_main::kSkipped;
  }
  if (corpus + static_cast<std::size_t>(seeds) == 0) {
    std::fprintf(stderr, "no input replayed from %s or the data seeds\n", argv[1]);
    return 1;
  }
  std::printf("%zu corpus, %zu regression and %ld data inputs replayed\n", corpus, regressions, seeds);
  return 0;
}
