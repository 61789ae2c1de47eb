// The scalar types of a PLY file and the reading of one value of them, binary or ascii,
// for io/ply_read.cc. Every failure throws std::runtime_error "SOURCE: what".
#pragma once

#include <cstddef>
#include <string>

namespace facets {

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

// The type of a "property" line's type name (char/int8 ... double/float64); false if none.
bool PlyTypeFromName(const std::string& name, PlyType* type);
// Bytes of one binary value.
size_t PlyTypeSize(PlyType type);
bool PlyTypeIsInteger(PlyType type);

// Throws std::runtime_error(source + ": " + what).
[[noreturn]] void FailPly(const std::string& source, const std::string& what);

// A value read from the file for a message, shortest exact form: "-1", "4e+09", "nan".
std::string FormatPlyNumber(double value);

// Reads one scalar of `type` at `*cursor`, advancing it; byte-swapped when `swap`; fails
// (naming `context`) when the data ends first. Every PLY scalar fits a double exactly
// (32-bit integers too).
double ReadBinaryScalar(const char** cursor, const char* end, PlyType type, bool swap,
                        const std::string& source, const std::string& context);

// Splits an ascii data line into numbers; locale-independent (std::from_chars). Keeps
// references to `line` and `source`: they must outlive it.
class PlyAsciiLine {
 public:
  PlyAsciiLine(const std::string& line, const std::string& source, size_t line_number)
      : line_(line), source_(source), line_number_(line_number) {}

  // The next number; fails naming the line and `context` when there is none or it is not
  // a number.
  double Next(const std::string& context);
  // An upper bound of the values left on the line (each needs a character and a space).
  size_t Left() const;
  bool AtEnd();

 private:
  void SkipSpace();

  const std::string& line_;
  const std::string& source_;
  size_t line_number_;
  size_t pos_ = 0;
};

}  // namespace facets
