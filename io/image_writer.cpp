#include "io/image_writer.h"

#include "io/atomic_file.h"
#include "io/image_encoder_module.h"

#include <dlfcn.h>

#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace strata {

namespace {
[[noreturn]] void fail_write(const std::filesystem::path& path, const std::string& reason) {
  throw std::runtime_error("write_image: cannot write '" + path.string() + "': " + reason);
}

// The encoder module, loaded once per process on the first image (io/image_encoder_module.h says why it is not
// linked in). It is looked for beside libstrata, found through dladdr on this function, which holds in the build
// tree and in an install alike; then by name, through the loader's search path. It is never unloaded.
struct EncoderModule {
  StrataEncodeImageFn encode = nullptr;
  std::string error;  // why it could not be loaded, when encode is null
};

const EncoderModule& encoder_module() {
  static const EncoderModule module = [] {
    EncoderModule m;
    std::vector<std::string> candidates;
    Dl_info self{};
    if (dladdr(reinterpret_cast<void*>(&encoder_module), &self) != 0 && self.dli_fname != nullptr)
      candidates.push_back((std::filesystem::path(self.dli_fname).parent_path() / STRATA_IMAGE_MODULE_FILE).string());
    candidates.emplace_back(STRATA_IMAGE_MODULE_FILE);
    for (const std::string& candidate : candidates) {
      void* handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (handle == nullptr) {
        const char* reason = dlerror();
        m.error += (m.error.empty() ? "" : "; ") + std::string(reason != nullptr ? reason : candidate);
        continue;
      }
      m.encode = reinterpret_cast<StrataEncodeImageFn>(dlsym(handle, STRATA_IMAGE_ENCODE_SYMBOL));
      if (m.encode != nullptr) break;
      m.error += (m.error.empty() ? "" : "; ") + candidate + " has no " STRATA_IMAGE_ENCODE_SYMBOL;
    }
    return m;
  }();
  return module;
}

}  // namespace

void write_image(const std::filesystem::path& path, int width, int height, int channels,
                 std::span<const std::uint8_t> pixels) {
  if (width <= 0 || height <= 0) fail_write(path, "image size must be positive");
  if (channels != 3 && channels != 4) fail_write(path, "channels must be 3 or 4, got " + std::to_string(channels));
  const std::size_t expected = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                               static_cast<std::size_t>(channels);
  if (pixels.size() != expected)
    fail_write(path, "got " + std::to_string(pixels.size()) + " bytes, expected " + std::to_string(expected));

  // Missing directories are the caller's mistake (usually a typo in --out); creating them silently would
  // scatter frames into a path nobody meant, so say which directory is missing instead.
  const std::filesystem::path parent = path.parent_path();
  std::error_code ec;
  if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
    fail_write(path, "directory '" + parent.string() + "' does not exist");

  // Encoded into memory, then written through write_file_atomically (io/atomic_file.h): a temporary sibling
  // renamed into place only when complete. Letting OpenImageIO write the file itself was rejected: its PNG writer
  // ignores a failing write (a full disk, a file-size limit) and reports success over a truncated frame.
  const EncoderModule& module = encoder_module();
  if (module.encode == nullptr) fail_write(path, "the image encoder module could not be loaded (" + module.error + ")");
  std::vector<unsigned char> encoded;
  std::string error;
  if (!module.encode(path.string().c_str(), width, height, channels, pixels.data(), &encoded, &error))
    fail_write(path, error);
  try {
    write_file_atomically(path, {reinterpret_cast<const char*>(encoded.data()), encoded.size()});
  } catch (const std::exception& e) {
    fail_write(path, e.what());
  }
}

}  // namespace strata
