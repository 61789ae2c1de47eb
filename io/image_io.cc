#include "io/image_io.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <stdexcept>

#include "io/atomic_file.h"
#include "io/input_file.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

template <typename T>
void Deinterleave(const std::vector<T>& interleaved, ImagePlanes* image) {
  const size_t plane = static_cast<size_t>(image->width) * image->height;
  const int channels = image->channels;
  for (int c = 0; c < channels; ++c) {
    float* out = image->data.data() + c * plane;
    for (size_t i = 0; i < plane; ++i) out[i] = static_cast<float>(interleaved[i * channels + c]);
  }
}

// Reads the whole image in the file's own type. A decoder that meets corrupt data may
// still return true and fill the rest with zeros (libtiff on a damaged deflate strip);
// its error is then only in has_error(), so that is an error here too.
template <typename T>
void ReadAs(OIIO::ImageInput* in, OIIO::TypeDesc type, const std::string& path,
            ImagePlanes* image) {
  std::vector<T> interleaved(static_cast<size_t>(image->width) * image->height *
                             image->channels);
  const bool read = in->read_image(0, 0, 0, image->channels, type, interleaved.data());
  if (!read || in->has_error()) {
    const std::string error = in->geterror();
    throw std::runtime_error(path + ": cannot decode the pixels (corrupt or truncated file)" +
                             (error.empty() ? std::string() : ": " + error));
  }
  Deinterleave(interleaved, image);
}

template <typename T>
std::vector<T> Interleave(const ImagePlanes& image, double max_value) {
  const size_t plane = static_cast<size_t>(image.width) * image.height;
  std::vector<T> out(plane * image.channels);
  for (int c = 0; c < image.channels; ++c) {
    const float* in = image.data.data() + c * plane;
    for (size_t i = 0; i < plane; ++i) {
      double v = std::isfinite(in[i]) ? std::round(static_cast<double>(in[i])) : 0.0;
      v = std::clamp(v, 0.0, max_value);
      out[i * image.channels + c] = static_cast<T>(v);
    }
  }
  return out;
}

}  // namespace

ImagePlanes ImagePlanes::Grey() const {
  ImagePlanes grey;
  grey.width = width;
  grey.height = height;
  grey.channels = 1;
  grey.bits = bits;
  const size_t plane = static_cast<size_t>(width) * height;
  grey.data.assign(plane, 0.0f);
  if (channels == 0) return grey;
  for (int c = 0; c < channels; ++c) {
    const float* in = data.data() + c * plane;
    for (size_t i = 0; i < plane; ++i) grey.data[i] += in[i];
  }
  const float scale = 1.0f / static_cast<float>(channels);
  for (float& v : grey.data) v *= scale;
  return grey;
}

namespace {

// Reads `path`; when `expected` is given, its size is checked against the camera's before
// any pixel is read (a wrong or damaged header must not size an allocation).
ImagePlanes ReadImageChecked(const std::string& path, const Camera* expected) {
  CheckInputFile(path, "image file");
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    throw std::runtime_error(path + ": cannot read image: " + OIIO::geterror());
  }
  const OIIO::ImageSpec& spec = in->spec();
  ImagePlanes image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.nchannels;
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0) {
    throw std::runtime_error(path + ": image has no pixels");
  }
  if (expected != nullptr && (image.width != expected->width || image.height != expected->height)) {
    throw std::runtime_error(path + ": image is " + std::to_string(image.width) + "x" +
                             std::to_string(image.height) + " pixels but camera " +
                             std::to_string(expected->camera_id) + " expects " +
                             std::to_string(expected->width) + "x" +
                             std::to_string(expected->height));
  }
  image.data.resize(static_cast<size_t>(image.width) * image.height * image.channels);
  // Read in the file's own type so values stay on its grey scale (OIIO would normalise
  // integers to 0..1 when converting to float).
  switch (spec.format.basetype) {
    case OIIO::TypeDesc::UINT8:
      image.bits = 8;
      ReadAs<uint8_t>(in.get(), OIIO::TypeDesc::UINT8, path, &image);
      break;
    case OIIO::TypeDesc::UINT16:
      image.bits = 16;
      ReadAs<uint16_t>(in.get(), OIIO::TypeDesc::UINT16, path, &image);
      break;
    case OIIO::TypeDesc::INT16:
      image.bits = 16;
      ReadAs<int16_t>(in.get(), OIIO::TypeDesc::INT16, path, &image);
      break;
    case OIIO::TypeDesc::HALF:
    case OIIO::TypeDesc::FLOAT:
    case OIIO::TypeDesc::DOUBLE:
      image.bits = 32;
      ReadAs<float>(in.get(), OIIO::TypeDesc::FLOAT, path, &image);
      break;
    default:
      throw std::runtime_error(path + ": unsupported pixel type " +
                               std::string(spec.format.c_str()) +
                               " (8/16-bit integer or float expected)");
  }
  in->close();
  return image;
}

}  // namespace

ImagePlanes ReadImage(const std::string& path) { return ReadImageChecked(path, nullptr); }

ImagePlanes ReadImageFor(const std::string& path, const Camera& camera) {
  return ReadImageChecked(path, &camera);
}

void WriteImage(const std::string& path, const ImagePlanes& image, int bits) {
  if (bits != 8 && bits != 16 && bits != 32) {
    throw std::invalid_argument(path + ": bits must be 8, 16 or 32, got " +
                                std::to_string(bits));
  }
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.data.size() != static_cast<size_t>(image.width) * image.height * image.channels) {
    throw std::invalid_argument(path + ": image planes are empty or inconsistent");
  }
  const std::string ext = Lower(fs::path(path).extension().string());
  const bool is_jpeg = ext == ".jpg" || ext == ".jpeg";
  if (bits == 32 && ext != ".tif" && ext != ".tiff" && ext != ".exr") {
    throw std::invalid_argument(path + ": 32-bit float images need .tif, .tiff or .exr");
  }
  if (bits == 16 && is_jpeg) throw std::invalid_argument(path + ": JPEG cannot store 16 bits");
  // The format comes from the final name; the pixels go to a unique temporary beside it
  // first (io/atomic_file.h).
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw std::runtime_error(path + ": no writer for this format: " + OIIO::geterror());
  const OIIO::TypeDesc type = bits == 8    ? OIIO::TypeDesc::UINT8
                              : bits == 16 ? OIIO::TypeDesc::UINT16
                                           : OIIO::TypeDesc::FLOAT;
  OIIO::ImageSpec spec(image.width, image.height, image.channels, type);
  if (is_jpeg) spec.attribute("CompressionQuality", 95);
  const std::string tmp = CreateTemporaryBeside(path);
  if (!out->open(tmp, spec)) {
    RemoveTemporary(tmp);
    throw std::runtime_error(path + ": cannot open for writing: " + out->geterror());
  }
  bool ok = false;
  if (bits == 8) {
    ok = out->write_image(type, Interleave<uint8_t>(image, 255.0).data());
  } else if (bits == 16) {
    ok = out->write_image(type, Interleave<uint16_t>(image, 65535.0).data());
  } else {
    const size_t plane = static_cast<size_t>(image.width) * image.height;
    std::vector<float> interleaved(plane * image.channels);
    for (int c = 0; c < image.channels; ++c) {
      for (size_t i = 0; i < plane; ++i) {
        interleaved[i * image.channels + c] = image.data[c * plane + i];
      }
    }
    ok = out->write_image(type, interleaved.data());
  }
  const std::string write_error = ok ? "" : out->geterror();
  const bool closed = out->close();
  if (!ok || !closed) {
    RemoveTemporary(tmp);
    throw std::runtime_error(path + ": write failed: " + write_error + out->geterror());
  }
  CommitTemporary(tmp, path);
}

}  // namespace facets
