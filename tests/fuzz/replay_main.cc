// Replays a fuzz target's inputs without libFuzzer (any compiler): calls the target's
// LLVMFuzzerTestOneInput on every file of the corpus folder and of the regressions folder.
//   fuzz_replay_<target> <corpus folder> [<regressions folder>]
// Fails when the corpus folder holds no input (a replay of nothing would pass unseen); a
// missing regressions folder is an empty one. A crash or an unexpected exception in the
// target ends the program abnormally, which is the finding.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
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

std::vector<std::uint8_t> Bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
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
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: %s <corpus folder> [<regressions folder>]\n", argv[0]);
    return 2;
  }
  const std::size_t corpus = replay_main::Replay(replay_main::InputsIn(argv[1]));
  if (corpus == 0) {
    std::fprintf(stderr, "no input in the corpus folder %s\n", argv[1]);
    return 1;
  }
  const std::size_t regressions = argc == 3 ? replay_main::Replay(replay_main::InputsIn(argv[2])) : 0;
  std::printf("%zu corpus and %zu regression inputs replayed\n", corpus, regressions);
  return 0;
}
