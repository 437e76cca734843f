#pragma once
// Every output file Strata writes (PNG frames, JSON reports, trace JSON/CSV, summaries, the body cache) goes
// through AtomicFile: the bytes are written to a temporary sibling (same directory, so the final rename never
// crosses a file system) and renamed over the target only once complete. A crash, a full disk or a thrown error
// therefore leaves either the previous file or none, never a truncated one that the next tool would take for
// valid. Writing in place and deleting on failure was rejected: it cannot help when the process dies mid-write.
#include <filesystem>
#include <string_view>

namespace strata {

class AtomicFile {
 public:
  // Picks a temporary name ".<target name>.<pid>.<n>.tmp" beside `target`; nothing is created yet.
  explicit AtomicFile(std::filesystem::path target);
  // Removes the temporary file unless commit() succeeded.
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // Where the writer must put the bytes.
  const std::filesystem::path& temp_path() const { return temp_; }
  const std::filesystem::path& target() const { return target_; }
  // Renames the temporary file over the target. Throws std::runtime_error naming the target on failure (the
  // temporary file is then removed).
  void commit();

 private:
  std::filesystem::path target_, temp_;
  bool committed_ = false;
};

// Writes `bytes` to `path` through an AtomicFile. Throws std::runtime_error naming the path on failure.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace strata
