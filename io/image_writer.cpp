#include "io/image_writer.h"

#include "io/atomic_file.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace strata {

namespace {
[[noreturn]] void fail(const std::filesystem::path& path, const std::string& reason) {
  throw std::runtime_error("write_image: cannot write '" + path.string() + "': " + reason);
}
}  // namespace

void write_image(const std::filesystem::path& path, int width, int height, int channels,
                 std::span<const std::uint8_t> pixels) {
  if (width <= 0 || height <= 0) fail(path, "image size must be positive");
  if (channels != 3 && channels != 4) fail(path, "channels must be 3 or 4, got " + std::to_string(channels));
  const std::size_t expected = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                               static_cast<std::size_t>(channels);
  if (pixels.size() != expected)
    fail(path, "got " + std::to_string(pixels.size()) + " bytes, expected " + std::to_string(expected));

  // Missing directories are the caller's mistake (usually a typo in --out); creating them silently would
  // scatter frames into a path nobody meant, so say which directory is missing instead.
  const std::filesystem::path parent = path.parent_path();
  std::error_code ec;
  if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
    fail(path, "directory '" + parent.string() + "' does not exist");

  // Encoded into memory, then written through write_file_atomically (io/atomic_file.h): a temporary sibling
  // renamed into place only when complete. Letting OpenImageIO write the file itself was rejected: its PNG writer
  // ignores a failing write (a full disk, a file-size limit) and reports success over a truncated frame.
  auto out = OIIO::ImageOutput::create(path.string());
  if (!out) fail(path, "no image format for this file name (" + OIIO::geterror() + ")");
  if (!out->supports("ioproxy")) fail(path, "the image format cannot be encoded in memory");
  std::vector<unsigned char> encoded;
  OIIO::Filesystem::IOVecOutput memory(encoded);
  OIIO::Filesystem::IOProxy* proxy = &memory;

  OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
  // Level 1 instead of the default 6: about 3x faster to encode for a modest size cost (notes, section 1).
  spec.attribute("png:compressionLevel", 1);
  spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  if (!out->open(path.string(), spec)) fail(path, out->geterror());
  const bool written = out->write_image(OIIO::TypeDesc::UINT8, pixels.data());
  const std::string write_error = written ? std::string{} : out->geterror();
  const bool closed = out->close();
  if (!written || !closed) fail(path, written ? out->geterror() : write_error);
  try {
    write_file_atomically(path, {reinterpret_cast<const char*>(encoded.data()), encoded.size()});
  } catch (const std::exception& e) {
    fail(path, e.what());
  }
}

}  // namespace strata
