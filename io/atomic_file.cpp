#include "io/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <system_error>

namespace strata {
namespace {
// Distinguishes concurrent writers of one process (threads writing frames); the pid distinguishes processes.
std::atomic<unsigned> g_sequence{0};
}  // namespace

AtomicFile::AtomicFile(std::filesystem::path target) : target_(std::move(target)) {
  // Appended piecewise: GCC 12 warns (-Wrestrict, a known false positive) on "." + std::string(...).
  std::string name(1, '.');
  name.append(target_.filename().string());
  name.append(".").append(std::to_string(::getpid()));
  name.append(".").append(std::to_string(g_sequence.fetch_add(1))).append(".tmp");
  temp_ = target_.parent_path() / name;
}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  std::error_code ec;
  std::filesystem::remove(temp_, ec);
}

void AtomicFile::commit() {
  std::error_code ec;
  std::filesystem::rename(temp_, target_, ec);
  if (ec) {
    // The reason is taken before the clean-up, whose own error_code would overwrite it ("rename failed: Success").
    const std::string reason = ec.message();
    std::error_code ignored;
    std::filesystem::remove(temp_, ignored);
    throw std::runtime_error("cannot write '" + target_.string() + "': rename failed: " + reason);
  }
  committed_ = true;
}

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes) {
  AtomicFile file(path);
  // stdio rather than ofstream: fclose reports the error of the last buffered write (a full disk shows up there).
  std::FILE* f = std::fopen(file.temp_path().c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write '" + path.string() + "': " + std::strerror(errno));
  const bool written = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  const int write_errno = errno;
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed)
    throw std::runtime_error("cannot write '" + path.string() + "': " + std::strerror(written ? errno : write_errno));
  file.commit();
}

}  // namespace strata
