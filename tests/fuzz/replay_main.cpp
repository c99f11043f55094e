// Replays fuzz inputs without libFuzzer (tests/fuzz/README.md): runs the fuzz target it is
// linked with on every file in the folders (or on the files) named on the command line, in
// name order, so that a normal build and ctest check every committed input: the seeds and the
// minimised crashes of past fuzzing runs. Exits 1 when an exception escapes the target (which
// catches InputError only), when the process grows beyond the fuzzers' -rss_limit_mb
// (README.md: 2048 MB), or when no input ran; a crash or a sanitizer report ends the process
// after the input's name was printed, and an input that never ends is left to the test's
// timeout. Each input's time is printed, never judged.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

// As the fuzzers' -rss_limit_mb in README.md: beyond it an input is a bug. (Time is printed,
// not judged: a test never fails on the clock; the fuzzers' -timeout judges hangs.)
constexpr long kRssLimitMb = 2048;

// The peak resident memory of this process so far.
long peakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024;  // kilobytes on Linux
}

}  // namespace

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

  int failed = 0;
  for (const fs::path& input : inputs) {
    std::printf("%s", input.c_str());
    std::fflush(stdout);  // named before a crash can end the process
    const auto start = std::chrono::steady_clock::now();
    std::ifstream in(input, std::ios::binary);
    // Exactly the input's size on the heap, as libFuzzer passes it, so an over-read is caught.
    const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                           std::istreambuf_iterator<char>());
    try {
      LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
    } catch (const std::exception& e) {
      ++failed;
      std::fprintf(stderr, "%s: escaped: %s\n", input.c_str(), e.what());
    } catch (...) {
      ++failed;
      std::fprintf(stderr, "%s: escaped: an exception not derived from std::exception\n",
                   input.c_str());
    }
    const std::chrono::duration<double, std::milli> took = std::chrono::steady_clock::now() - start;
    std::printf(" (%.0f ms)\n", took.count());
    std::fflush(stdout);  // in order with the messages on stderr
    if (peakRssMb() > kRssLimitMb) {
      std::fprintf(stderr, "%s: the process grew to %ld MB, beyond %ld MB\n", input.c_str(),
                   peakRssMb(), kRssLimitMb);
      return 1;
    }
  }
  std::printf("%zu inputs ran, %d failed\n", inputs.size(), failed);
  return failed > 0 || inputs.empty() ? 1 : 0;
}
