#pragma once
// The seam between io/image_writer.cpp (inside libstrata) and io/image_encoder_oiio.cpp, a module of its own that
// libstrata loads with dlopen on the first image it writes. Why a module: OpenImageIO's dependency closure on
// Debian 12 is about 250 shared libraries (OpenCV, GDAL, FFmpeg, GStreamer, ...), and linking it into libstrata
// made every process that loads the engine pay for them at start, about 0.4 s and 130 MB of mappings, whether or
// not it ever wrote an image (`strata --version`, `strata info`, each of the 500-odd test processes).
#include <cstdint>
#include <string>
#include <vector>

// File name of the module, next to libstrata in the build tree and in the install.
#define STRATA_IMAGE_MODULE_FILE "libstrata_image_oiio.so"
// Symbol the module exports.
#define STRATA_IMAGE_ENCODE_SYMBOL "strata_encode_image"

// Encodes `pixels` (rows top to bottom, `channels` uint8 per pixel) in the format `path`'s extension names,
// into `encoded`; nothing is written to disk. Returns false with `error` set when it cannot. Arguments are
// checked by the caller. Both sides are built together by one compiler, so C++ types may cross; extern "C" only
// keeps the symbol's name plain for dlsym.
extern "C" bool strata_encode_image(const char* path, int width, int height, int channels,
                                    const std::uint8_t* pixels, std::vector<unsigned char>* encoded,
                                    std::string* error) noexcept;
using StrataEncodeImageFn = decltype(&strata_encode_image);
