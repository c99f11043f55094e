// Replays fuzz inputs without libFuzzer (tests/fuzz/README.md): runs the fuzz target it is
// linked with on every file in the folders (or on the files) named on the command line, in
// name order, so that a normal build and ctest check every committed input: the seeds and the
// minimised crashes of past fuzzing runs. Exits 1 when an exception escapes the target (which
// catches InputError only) or when no input ran; a crash or a sanitizer report ends the
// process, after the input's name was printed.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const fs::path arg = argv[i];
    std::error_code ec;
    if (fs::is_directory(arg, ec)) {
      for (const auto& entry : fs::directory_iterator(arg))
        if (entry.is_regular_file()) inputs.push_back(entry.path());
    } else if (fs::is_regular_file(arg, ec)) {
      inputs.push_back(arg);
    } else {
      std::fprintf(stderr, "%s: no such file or folder\n", argv[i]);
      return 2;
    }
  }
  std::sort(inputs.begin(), inputs.end());

  int escaped = 0;
  for (const fs::path& input : inputs) {
    std::printf("%s\n", input.c_str());
    std::fflush(stdout);  // named before a crash can end the process
    std::ifstream in(input, std::ios::binary);
    // Exactly the input's size on the heap, as libFuzzer passes it, so an over-read is caught.
    const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                           std::istreambuf_iterator<char>());
    try {
      LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
    } catch (const std::exception& e) {
      ++escaped;
      std::fprintf(stderr, "%s: escaped: %s\n", input.c_str(), e.what());
    } catch (...) {
      ++escaped;
      std::fprintf(stderr, "%s: escaped: an exception not derived from std::exception\n",
                   input.c_str());
    }
  }
  std::printf("%zu inputs ran, %d escaped\n", inputs.size(), escaped);
  return escaped > 0 || inputs.empty() ? 1 : 0;
}
