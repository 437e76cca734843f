// The OpenImageIO side of image writing, built as its own module (io/image_encoder_module.h says why).
#include "io/image_encoder_module.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <exception>

extern "C" __attribute__((visibility("default"))) bool strata_encode_image(
    const char* path, int width, int height, int channels, const std::uint8_t* pixels,
    std::vector<unsigned char>* encoded, std::string* error) noexcept {
  try {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) {
      *error = "no image format for this file name (" + OIIO::geterror() + ")";
      return false;
    }
    if (!out->supports("ioproxy")) {
      *error = "the image format cannot be encoded in memory";
      return false;
    }
    OIIO::Filesystem::IOVecOutput memory(*encoded);
    OIIO::Filesystem::IOProxy* proxy = &memory;
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
    // Level 1 instead of the default 6: about 3x faster to encode for a modest size cost (notes, section 1).
    spec.attribute("png:compressionLevel", 1);
    spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    if (!out->open(path, spec)) {
      *error = out->geterror();
      return false;
    }
    const bool written = out->write_image(OIIO::TypeDesc::UINT8, pixels);
    const std::string write_error = written ? std::string{} : out->geterror();
    const bool closed = out->close();
    if (!written || !closed) {
      *error = written ? out->geterror() : write_error;
      return false;
    }
    return true;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}
