#include "io/tiff_strips.h"

#include <tiffio.h>

#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <vector>

namespace facets {
namespace {

// libtiff's messages for one open file: the first error kept, warnings (unknown tags,
// and the like) dropped; neither goes to libtiff's global handlers (stderr).
int KeepFirstError(TIFF*, void* user_data, const char* module, const char* format, va_list args) {
  auto* error = static_cast<std::string*>(user_data);
  if (error->empty()) {
    char text[512];
    std::vsnprintf(text, sizeof(text), format, args);
    *error = (module != nullptr ? std::string(module) + ": " : std::string()) + text;
  }
  return 1;
}
int DropWarning(TIFF*, void*, const char*, const char*, va_list) { return 1; }

struct CloseTiff {
  void operator()(TIFF* tiff) const { TIFFClose(tiff); }
};

}  // namespace

void CheckDeflateTiffStrips(const std::string& path) {
  std::string error;
  TIFFOpenOptions* options = TIFFOpenOptionsAlloc();
  TIFFOpenOptionsSetErrorHandlerExtR(options, KeepFirstError, &error);
  TIFFOpenOptionsSetWarningHandlerExtR(options, DropWarning, nullptr);
  const std::unique_ptr<TIFF, CloseTiff> tiff(TIFFOpenExt(path.c_str(), "r", options));
  TIFFOpenOptionsFree(options);
  if (!tiff) throw std::runtime_error(path + ": cannot read TIFF: " + error);
  uint16_t compression = COMPRESSION_NONE;
  TIFFGetFieldDefaulted(tiff.get(), TIFFTAG_COMPRESSION, &compression);
  const bool deflate = compression == COMPRESSION_ADOBE_DEFLATE || compression == COMPRESSION_DEFLATE;
  if (!deflate || TIFFIsTiled(tiff.get())) return;
  const tmsize_t strip_bytes = TIFFStripSize(tiff.get());
  if (strip_bytes <= 0) throw std::runtime_error(path + ": TIFF has no strip size: " + error);
  std::vector<uint8_t> strip(static_cast<size_t>(strip_bytes));
  const uint32_t strips = TIFFNumberOfStrips(tiff.get());
  for (uint32_t s = 0; s < strips; ++s) {
    if (TIFFReadEncodedStrip(tiff.get(), s, strip.data(), strip_bytes) < 0) {
      throw std::runtime_error(path + ": cannot decode the pixels of strip " + std::to_string(s + 1) + " of " +
                               std::to_string(strips) + " (corrupt deflate data): " + error);
    }
  }
}

}  // namespace facets
