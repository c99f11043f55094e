#include "export/atomic_file.h"

#include <unistd.h>

#include <system_error>

namespace glint {

AtomicFile::AtomicFile(std::filesystem::path target) : target_(std::move(target)) {
  // Same folder as the target, so the final rename never crosses file systems.
  temporary_ = target_;
  temporary_ += ".tmp." + std::to_string(::getpid());
  out_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!out_)
    throw OutputError("cannot create " + target_.string() + " (is the folder there and writable?)");
}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  out_.close();
  std::error_code ignored;
  std::filesystem::remove(temporary_, ignored);
}

void AtomicFile::commit() {
  out_.flush();
  const bool written = static_cast<bool>(out_);
  out_.close();
  if (!written || out_.fail()) throw OutputError("cannot write " + target_.string());
  std::error_code ec;
  std::filesystem::rename(temporary_, target_, ec);
  if (ec) throw OutputError("cannot write " + target_.string() + ": " + ec.message());
  committed_ = true;
}

}  // namespace glint
