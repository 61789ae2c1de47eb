// PLY scalar types and the reading of one value; see io/ply_values.h.
#include "io/ply_values.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace facets {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the binary PLY reader assumes a little-endian host");

template <typename T>
double Load(const unsigned char* bytes) {
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return static_cast<double>(value);
}

}  // namespace

bool PlyTypeFromName(const std::string& name, PlyType* type) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},
      {"uchar", PlyType::kUint8},    {"uint8", PlyType::kUint8},
      {"short", PlyType::kInt16},    {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},
      {"int", PlyType::kInt32},      {"int32", PlyType::kInt32},
      {"uint", PlyType::kUint32},    {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32},
      {"double", PlyType::kFloat64}, {"float64", PlyType::kFloat64},
  };
  for (const auto& [n, t] : kNames) {
    if (name == n) {
      *type = t;
      return true;
    }
  }
  return false;
}

size_t PlyTypeSize(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

bool PlyTypeIsInteger(PlyType type) {
  return type != PlyType::kFloat32 && type != PlyType::kFloat64;
}

void FailPly(const std::string& source, const std::string& what) {
  throw std::runtime_error(source + ": " + what);
}

std::string FormatPlyNumber(double value) {
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof(text), value).ptr);
}

double ReadBinaryScalar(const char** cursor, const char* end, PlyType type, bool swap,
                        const std::string& source, const std::string& context) {
  const size_t size = PlyTypeSize(type);
  if (static_cast<size_t>(end - *cursor) < size) {
    FailPly(source, "truncated binary data in " + context);
  }
  unsigned char bytes[8];
  std::memcpy(bytes, *cursor, size);
  *cursor += size;
  if (swap) std::reverse(bytes, bytes + size);
  switch (type) {
    case PlyType::kInt8: return Load<int8_t>(bytes);
    case PlyType::kUint8: return Load<uint8_t>(bytes);
    case PlyType::kInt16: return Load<int16_t>(bytes);
    case PlyType::kUint16: return Load<uint16_t>(bytes);
    case PlyType::kInt32: return Load<int32_t>(bytes);
    case PlyType::kUint32: return Load<uint32_t>(bytes);
    case PlyType::kFloat32: return Load<float>(bytes);
    case PlyType::kFloat64: return Load<double>(bytes);
  }
  return 0.0;
}

void PlyAsciiLine::SkipSpace() {
  while (pos_ < line_.size() && std::isspace(static_cast<unsigned char>(line_[pos_]))) ++pos_;
}

double PlyAsciiLine::Next(const std::string& context) {
  SkipSpace();
  if (pos_ >= line_.size()) {
    FailPly(source_, "line " + std::to_string(line_number_) + ": too few values for " + context);
  }
  size_t start = pos_;
  while (pos_ < line_.size() && !std::isspace(static_cast<unsigned char>(line_[pos_]))) ++pos_;
  const char* first = line_.data() + start;
  const char* last = line_.data() + pos_;
  if (*first == '+') ++first;
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (ec != std::errc() || ptr != last) {
    FailPly(source_, "line " + std::to_string(line_number_) + ": '" +
                         line_.substr(start, pos_ - start) + "' is not a number (" + context + ")");
  }
  return value;
}

size_t PlyAsciiLine::Left() const { return (line_.size() - std::min(pos_, line_.size()) + 1) / 2; }

bool PlyAsciiLine::AtEnd() {
  SkipSpace();
  return pos_ >= line_.size();
}

}  // namespace facets
