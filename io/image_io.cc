#include "io/image_io.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "io/atomic_file.h"
#include "io/input_file.h"
#include "io/tiff_strips.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// Rows of an open image in a pixel type of the caller's choice, interleaved. Tiled files
// are read a band of tile rows at a time (OpenImageIO 2.4.7's read_scanlines divides by
// zero on them: SIGFPE); the last band is kept for the next rows. After each read the
// decoder's messages are errors: a decoder that meets corrupt data may still return
// true and fill the rest with grey or zeros (libjpeg on a truncated JPEG, libtiff on a
// damaged LZW strip), and has_error() stays false there, only geterror() tells.
class RowReader {
 public:
  RowReader(OIIO::ImageInput* in, std::string path) : in_(in), path_(std::move(path)) {}
  const OIIO::ImageSpec& spec() const { return in_->spec(); }

  void Read(int y0, int y1, OIIO::TypeDesc type, void* rows) {
    const OIIO::ImageSpec& spec = in_->spec();
    const size_t row_bytes = static_cast<size_t>(spec.width) * spec.nchannels * type.size();
    bool ok = true;
    if (spec.tile_width <= 0) {
      ok = in_->read_scanlines(0, 0, y0, y1, 0, 0, spec.nchannels, type, rows);
    } else {
      for (int y = y0; y < y1; ++y) {
        ok = HoldBand(y, type, row_bytes);
        if (!ok) break;
        std::copy_n(band_.data() + (y - band_y0_) * row_bytes, row_bytes,
                    static_cast<char*>(rows) + (y - y0) * row_bytes);
      }
    }
    const std::string error = in_->geterror();
    if (!ok || !error.empty()) {
      throw std::runtime_error(path_ + ": cannot decode the pixels of rows " + std::to_string(y0) + " to " +
                               std::to_string(y1) + " (corrupt or truncated file)" +
                               (error.empty() ? std::string() : ": " + error));
    }
  }

 private:
  // The band of tile rows holding row y in band_.
  bool HoldBand(int y, OIIO::TypeDesc type, size_t row_bytes) {
    if (y >= band_y0_ && y < band_y1_ && type == band_type_) return true;
    const OIIO::ImageSpec& spec = in_->spec();
    band_y0_ = y / spec.tile_height * spec.tile_height;
    band_y1_ = std::min(spec.height, band_y0_ + spec.tile_height);
    band_type_ = type;
    band_.resize(row_bytes * (band_y1_ - band_y0_));
    return in_->read_tiles(0, 0, 0, spec.width, band_y0_, band_y1_, 0, 1, 0, spec.nchannels, type, band_.data());
  }

  OIIO::ImageInput* in_;
  std::string path_;
  std::vector<char> band_;
  int band_y0_ = 0, band_y1_ = 0;
  OIIO::TypeDesc band_type_;
};

// Rows [y0, y1) of the open image, in the file's own type T (so values stay on its grey
// scale: OIIO would normalise integers to 0..1 when converting to float), into rows
// [y0, y1) of *image (plane-major, image->y0 = first row held).
template <typename T>
void ReadRowsAs(RowReader* reader, OIIO::TypeDesc type, int y0, int y1, ImagePlanes* image) {
  const size_t row = static_cast<size_t>(image->width) * image->channels;
  std::vector<T> interleaved(row * (y1 - y0));
  reader->Read(y0, y1, type, interleaved.data());
  const int channels = image->channels;
  for (int c = 0; c < channels; ++c) {
    for (int y = y0; y < y1; ++y) {
      float* out = image->Row(c, y);
      const T* in_row = interleaved.data() + (y - y0) * row;
      for (int x = 0; x < image->width; ++x) out[x] = static_cast<float>(in_row[x * channels + c]);
    }
  }
}

void ReadRows(RowReader* reader, int y0, int y1, ImagePlanes* image) {
  switch (image->bits) {
    case 8:
      return ReadRowsAs<uint8_t>(reader, OIIO::TypeDesc::UINT8, y0, y1, image);
    case 16:
      if (reader->spec().format.basetype == OIIO::TypeDesc::INT16) {
        return ReadRowsAs<int16_t>(reader, OIIO::TypeDesc::INT16, y0, y1, image);
      }
      return ReadRowsAs<uint16_t>(reader, OIIO::TypeDesc::UINT16, y0, y1, image);
    default:
      return ReadRowsAs<float>(reader, OIIO::TypeDesc::FLOAT, y0, y1, image);
  }
}

// The open file's size and bit depth; throws naming the file for an image without
// pixels or of an unsupported pixel type.
ImageHeader HeaderOf(const OIIO::ImageSpec& spec, const std::string& path) {
  ImageHeader header;
  header.width = spec.width;
  header.height = spec.height;
  header.channels = spec.nchannels;
  if (header.width <= 0 || header.height <= 0 || header.channels <= 0) {
    throw std::runtime_error(path + ": image has no pixels");
  }
  switch (spec.format.basetype) {
    case OIIO::TypeDesc::UINT8:
      header.bits = 8;
      break;
    case OIIO::TypeDesc::UINT16:
    case OIIO::TypeDesc::INT16:
      header.bits = 16;
      break;
    case OIIO::TypeDesc::HALF:
    case OIIO::TypeDesc::FLOAT:
    case OIIO::TypeDesc::DOUBLE:
      header.bits = 32;
      break;
    default:
      throw std::runtime_error(path + ": unsupported pixel type " + std::string(spec.format.c_str()) +
                               " (8/16-bit integer or float expected)");
  }
  return header;
}

std::unique_ptr<OIIO::ImageInput> OpenImage(const std::string& path) {
  CheckInputFile(path, "image file");
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw std::runtime_error(path + ": cannot read image: " + OIIO::geterror());
  return in;
}

// The open image, about to be decoded: a deflate TIFF's strips are decoded by libtiff
// first (io/tiff_strips.h), as OpenImageIO would not report damage in them.
void CheckBeforeDecoding(const OIIO::ImageInput& in, const std::string& path) {
  if (std::string(in.format_name()) == "tiff") CheckDeflateTiffStrips(path);
}

// An empty image of the header's size holding rows [y0, y0 + rows).
ImagePlanes RowsOf(const ImageHeader& header, int y0, int rows) {
  ImagePlanes image;
  image.width = header.width;
  image.height = rows;
  image.channels = header.channels;
  image.bits = header.bits;
  image.y0 = y0;
  image.data.resize(static_cast<size_t>(header.width) * rows * header.channels);
  return image;
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
  grey.x0 = x0;
  grey.y0 = y0;
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

void ImagePlanes::GetRow(int y, float* row) const {
  for (int c = 0; c < channels; ++c) std::copy_n(Row(c, y), width, row + static_cast<size_t>(c) * width);
}

void ImagePlanes::SetRow(int y, const float* row) {
  for (int c = 0; c < channels; ++c) std::copy_n(row + static_cast<size_t>(c) * width, width, Row(c, y));
}

ImageHeader ReadImageHeader(const std::string& path) {
  auto in = OpenImage(path);
  return HeaderOf(in->spec(), path);
}

ImagePlanes ReadImage(const std::string& path) {
  auto in = OpenImage(path);
  const ImageHeader header = HeaderOf(in->spec(), path);
  ImagePlanes image = RowsOf(header, 0, header.height);
  CheckBeforeDecoding(*in, path);
  RowReader reader(in.get(), path);
  ReadRows(&reader, 0, header.height, &image);
  in->close();
  return image;
}

void ForEachImageStrip(const std::string& path, int rows, int overlap,
                       const std::function<void(const ImagePlanes&)>& strip) {
  if (rows < 1 || overlap < 0 || overlap >= rows) {
    throw std::invalid_argument(path + ": strips need rows >= 1 and 0 <= overlap < rows");
  }
  auto in = OpenImage(path);
  const ImageHeader header = HeaderOf(in->spec(), path);
  CheckBeforeDecoding(*in, path);
  RowReader reader(in.get(), path);
  ImagePlanes previous;
  for (int y0 = 0; y0 < header.height; y0 += rows - overlap) {
    const int held = std::min(rows, header.height - y0);
    ImagePlanes current = RowsOf(header, y0, held);
    // The rows shared with the previous strip are copied, not read again: readers of
    // sequential formats (JPEG) would decode the file from its start to go back.
    const int shared = y0 > 0 ? std::min(overlap, held) : 0;
    for (int c = 0; c < header.channels && shared > 0; ++c) {
      std::copy_n(previous.Row(c, y0), static_cast<size_t>(header.width) * shared, current.Row(c, y0));
    }
    ReadRows(&reader, y0 + shared, y0 + held, &current);
    strip(current);
    if (y0 + held >= header.height) break;
    previous = std::move(current);
  }
  in->close();
}

// The camera's size is checked against the header before any pixel is read: a wrong or
// damaged header must not size an allocation.
ImagePlanes ReadImageFor(const std::string& path, const Camera& camera) {
  CheckImageHeader(path, camera);
  return ReadImage(path);
}

ImageHeader CheckImageHeader(const std::string& path, const Camera& camera) {
  const ImageHeader image = ReadImageHeader(path);
  if (image.width != camera.width || image.height != camera.height) {
    throw std::runtime_error(path + ": image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                             " pixels but camera " + std::to_string(camera.camera_id) + " expects " +
                             std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
  return image;
}

void CheckImageHeaders(const ImageBlock& block) {
  for (const BlockImage& image : block.images) CheckImageHeader(image.path, block.CameraOf(image));
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
