#include "io/ply_io.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <locale>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "io/atomic_file.h"

namespace facets {
namespace {

static_assert(std::endian::native == std::endian::little,
              "WritePly and the binary reader assume a little-endian host");

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

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

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };

[[noreturn]] void Fail(const std::string& source, const std::string& what) {
  throw std::runtime_error(source + ": " + what);
}

// Reads one scalar of `type` at `*cursor`, advancing it; fails (naming `context`) when
// the data ends first. Every PLY scalar fits a double exactly (32-bit integers too).
double ReadBinaryScalar(const char** cursor, const char* end, PlyType type, bool swap,
                        const std::string& source, const std::string& context) {
  const size_t size = PlyTypeSize(type);
  if (static_cast<size_t>(end - *cursor) < size) Fail(source, "truncated binary data in " + context);
  unsigned char bytes[8];
  std::memcpy(bytes, *cursor, size);
  *cursor += size;
  if (swap) std::reverse(bytes, bytes + size);
  switch (type) {
    case PlyType::kInt8: {
      int8_t v;
      std::memcpy(&v, bytes, 1);
      return v;
    }
    case PlyType::kUint8:
      return bytes[0];
    case PlyType::kInt16: {
      int16_t v;
      std::memcpy(&v, bytes, 2);
      return v;
    }
    case PlyType::kUint16: {
      uint16_t v;
      std::memcpy(&v, bytes, 2);
      return v;
    }
    case PlyType::kInt32: {
      int32_t v;
      std::memcpy(&v, bytes, 4);
      return v;
    }
    case PlyType::kUint32: {
      uint32_t v;
      std::memcpy(&v, bytes, 4);
      return v;
    }
    case PlyType::kFloat32: {
      float v;
      std::memcpy(&v, bytes, 4);
      return v;
    }
    case PlyType::kFloat64: {
      double v;
      std::memcpy(&v, bytes, 8);
      return v;
    }
  }
  return 0.0;
}

// Splits an ascii data line into numbers; locale-independent (std::from_chars).
class AsciiLine {
 public:
  AsciiLine(const std::string& line, const std::string& source, size_t line_number)
      : line_(line), source_(source), line_number_(line_number) {}

  double Next(const std::string& context) {
    while (pos_ < line_.size() && std::isspace(static_cast<unsigned char>(line_[pos_]))) ++pos_;
    if (pos_ >= line_.size()) {
      Fail(source_, "line " + std::to_string(line_number_) + ": too few values for " + context);
    }
    size_t start = pos_;
    while (pos_ < line_.size() && !std::isspace(static_cast<unsigned char>(line_[pos_]))) ++pos_;
    const char* first = line_.data() + start;
    const char* last = line_.data() + pos_;
    if (*first == '+') ++first;
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || ptr != last) {
      Fail(source_, "line " + std::to_string(line_number_) + ": '" +
                        line_.substr(start, pos_ - start) + "' is not a number (" + context + ")");
    }
    return value;
  }

  bool AtEnd() {
    while (pos_ < line_.size() && std::isspace(static_cast<unsigned char>(line_[pos_]))) ++pos_;
    return pos_ >= line_.size();
  }

 private:
  const std::string& line_;
  const std::string& source_;
  size_t line_number_;
  size_t pos_ = 0;
};

// Which MeshData field a vertex property fills.
enum class VertexSlot { kSkip, kX, kY, kZ, kNx, kNy, kNz, kRed, kGreen, kBlue, kSigma, kViews };

VertexSlot VertexSlotOf(const std::string& name) {
  if (name == "x") return VertexSlot::kX;
  if (name == "y") return VertexSlot::kY;
  if (name == "z") return VertexSlot::kZ;
  if (name == "nx") return VertexSlot::kNx;
  if (name == "ny") return VertexSlot::kNy;
  if (name == "nz") return VertexSlot::kNz;
  if (name == "red" || name == "r" || name == "diffuse_red") return VertexSlot::kRed;
  if (name == "green" || name == "g" || name == "diffuse_green") return VertexSlot::kGreen;
  if (name == "blue" || name == "b" || name == "diffuse_blue") return VertexSlot::kBlue;
  if (name == "sigma") return VertexSlot::kSigma;
  if (name == "views") return VertexSlot::kViews;
  return VertexSlot::kSkip;
}

std::string Trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

}  // namespace

void MeshData::Check(const std::string& source_name) const {
  const size_t nv = vertices.size();
  auto check_size = [&](size_t size, size_t expected, const char* what) {
    if (size != 0 && size != expected) {
      throw std::invalid_argument(source_name + ": " + what + " has " + std::to_string(size) +
                                  " entries, expected 0 or " + std::to_string(expected));
    }
  };
  check_size(normals.size(), nv, "normals");
  check_size(colors.size(), nv, "colors");
  check_size(sigma.size(), nv, "sigma");
  check_size(views.size(), nv, "views");
  check_size(face_labels.size(), faces.size(), "face_labels");
  for (size_t f = 0; f < faces.size(); ++f) {
    for (int c = 0; c < 3; ++c) {
      if (faces[f][c] < 0 || static_cast<size_t>(faces[f][c]) >= nv) {
        throw std::invalid_argument(source_name + ": face " + std::to_string(f) +
                                    " has vertex index " + std::to_string(faces[f][c]) +
                                    " out of range (" + std::to_string(nv) + " vertices)");
      }
    }
  }
}

namespace {

// "comment facets_origin X Y Z" / "comment facets_crs CRS" (see MeshData::origin); any
// other comment is ignored.
void ReadFacetsComment(std::istringstream& ls, const std::string& src, const std::string& where,
                       Eigen::Vector3d* origin, std::string* crs) {
  std::string key;
  ls >> key;
  if (key == "facets_origin") {
    for (int c = 0; c < 3; ++c) ls >> (*origin)[c];
    if (!ls || !origin->allFinite()) Fail(src, where + "malformed facets_origin comment");
  } else if (key == "facets_crs") {
    std::getline(ls >> std::ws, *crs);
    if (crs->empty()) Fail(src, where + "empty facets_crs comment");
  }
}

void WriteFacetsComments(const Eigen::Vector3d& origin, const std::string& crs,
                         const std::string& path, std::ostringstream& header) {
  if (!origin.allFinite()) throw std::invalid_argument(path + ": origin is not finite");
  if (crs.find('\n') != std::string::npos) {
    throw std::invalid_argument(path + ": crs must be one line");
  }
  if (!origin.isZero(0.0)) {
    header << "comment facets_origin";
    for (int c = 0; c < 3; ++c) {
      // Shortest fixed-point decimals that read back to the same double.
      char buffer[400];
      const auto result =
          std::to_chars(buffer, buffer + sizeof(buffer), origin[c], std::chars_format::fixed);
      header << ' ' << std::string_view(buffer, result.ptr - buffer);
    }
    header << "\n";
  }
  if (!crs.empty()) header << "comment facets_crs " << crs << "\n";
}

}  // namespace

MeshData ReadPly(std::istream& in, const std::string& source_name) {
  const std::string& src = source_name;
  std::string line;
  size_t line_number = 0;
  auto next_header_line = [&]() -> bool {
    if (!std::getline(in, line)) return false;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  };

  if (!next_header_line() || Trim(line) != "ply") Fail(src, "not a PLY file (first line is not 'ply')");

  PlyFormat format = PlyFormat::kAscii;
  Eigen::Vector3d mesh_origin = Eigen::Vector3d::Zero();
  std::string mesh_crs;
  bool have_format = false;
  std::vector<PlyElement> elements;
  bool header_done = false;
  while (next_header_line()) {
    std::istringstream ls(line);
    ls.imbue(std::locale::classic());
    std::string keyword;
    ls >> keyword;
    const std::string where = "line " + std::to_string(line_number) + ": ";
    if (keyword == "comment") {
      ReadFacetsComment(ls, src, where, &mesh_origin, &mesh_crs);
      continue;
    }
    if (keyword.empty() || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      header_done = true;
      break;
    }
    if (keyword == "format") {
      std::string name, version;
      ls >> name >> version;
      if (name == "ascii") {
        format = PlyFormat::kAscii;
      } else if (name == "binary_little_endian") {
        format = PlyFormat::kBinaryLittle;
      } else if (name == "binary_big_endian") {
        format = PlyFormat::kBinaryBig;
      } else {
        Fail(src, where + "unknown PLY format '" + name + "'");
      }
      have_format = true;
    } else if (keyword == "element") {
      PlyElement element;
      long long count = -1;
      ls >> element.name >> count;
      if (!ls || count < 0) Fail(src, where + "malformed element line '" + line + "'");
      element.count = static_cast<size_t>(count);
      elements.push_back(element);
    } else if (keyword == "property") {
      if (elements.empty()) Fail(src, where + "property before any element");
      PlyProperty property;
      std::string type_name;
      ls >> type_name;
      if (type_name == "list") {
        std::string count_name, item_name;
        ls >> count_name >> item_name >> property.name;
        if (!ls) Fail(src, where + "malformed list property '" + line + "'");
        if (!PlyTypeFromName(count_name, &property.count_type) ||
            !PlyTypeIsInteger(property.count_type)) {
          Fail(src, where + "bad list count type '" + count_name + "'");
        }
        if (!PlyTypeFromName(item_name, &property.type)) {
          Fail(src, where + "unknown property type '" + item_name + "'");
        }
        property.is_list = true;
      } else {
        ls >> property.name;
        if (!ls) Fail(src, where + "malformed property line '" + line + "'");
        if (!PlyTypeFromName(type_name, &property.type)) {
          Fail(src, where + "unknown property type '" + type_name + "'");
        }
      }
      elements.back().properties.push_back(property);
    } else {
      Fail(src, where + "unknown header keyword '" + keyword + "'");
    }
  }
  if (!header_done) Fail(src, "truncated header (no end_header)");
  if (!have_format) Fail(src, "header has no format line");

  MeshData mesh;
  mesh.origin = mesh_origin;
  mesh.crs = mesh_crs;
  const bool binary = format != PlyFormat::kAscii;
  const bool swap = format == PlyFormat::kBinaryBig;
  std::string data;
  if (binary) {
    data.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const char* cursor = data.data();
  const char* end = data.data() + data.size();

  bool have_xyz = false;
  std::vector<double> values;   // one element instance, scalars in property order
  std::vector<double> list;     // the list of the current list property
  for (const PlyElement& element : elements) {
    const bool is_vertex = element.name == "vertex";
    const bool is_face = element.name == "face";
    std::vector<VertexSlot> slots(element.properties.size(), VertexSlot::kSkip);
    int face_list = -1, face_label = -1;
    bool has[12] = {};
    if (is_vertex) {
      for (size_t p = 0; p < element.properties.size(); ++p) {
        if (element.properties[p].is_list) continue;
        slots[p] = VertexSlotOf(element.properties[p].name);
        has[static_cast<int>(slots[p])] = true;
      }
      have_xyz = has[int(VertexSlot::kX)] && has[int(VertexSlot::kY)] && has[int(VertexSlot::kZ)];
      if (!have_xyz) Fail(src, "vertex element lacks x, y or z");
      mesh.vertices.reserve(element.count);
      if (has[int(VertexSlot::kNx)] && has[int(VertexSlot::kNy)] && has[int(VertexSlot::kNz)]) {
        mesh.normals.reserve(element.count);
      }
    }
    const bool want_normals =
        is_vertex && has[int(VertexSlot::kNx)] && has[int(VertexSlot::kNy)] && has[int(VertexSlot::kNz)];
    const bool want_colors = is_vertex && has[int(VertexSlot::kRed)] &&
                             has[int(VertexSlot::kGreen)] && has[int(VertexSlot::kBlue)];
    if (is_face) {
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& prop = element.properties[p];
        if (prop.is_list && (prop.name == "vertex_indices" || prop.name == "vertex_index")) {
          if (!PlyTypeIsInteger(prop.type)) Fail(src, "face vertex indices are not integers");
          face_list = static_cast<int>(p);
        } else if (!prop.is_list && (prop.name == "label" || prop.name == "region")) {
          face_label = static_cast<int>(p);
        }
      }
      if (face_list < 0) Fail(src, "face element has no vertex_indices list");
    }

    for (size_t i = 0; i < element.count; ++i) {
      const std::string context = element.name + " " + std::to_string(i);
      std::optional<AsciiLine> ascii;
      if (!binary) {
        do {
          if (!std::getline(in, line)) {
            Fail(src, "truncated ascii data: expected " + std::to_string(element.count) + " " +
                          element.name + " lines, found " + std::to_string(i));
          }
          ++line_number;
          if (!line.empty() && line.back() == '\r') line.pop_back();
        } while (Trim(line).empty());
        ascii.emplace(line, src, line_number);
      }
      auto read = [&](PlyType type) {
        return binary ? ReadBinaryScalar(&cursor, end, type, swap, src, context)
                      : ascii->Next(context);
      };
      values.assign(element.properties.size(), 0.0);
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& prop = element.properties[p];
        if (!prop.is_list) {
          values[p] = read(prop.type);
          continue;
        }
        const double count = read(prop.count_type);
        if (count < 0 || count != std::floor(count)) {
          Fail(src, context + ": bad list length " + std::to_string(count));
        }
        const size_t n = static_cast<size_t>(count);
        if (is_face && static_cast<int>(p) == face_list) {
          list.resize(n);
          for (size_t k = 0; k < n; ++k) list[k] = read(prop.type);
        } else if (binary) {
          const size_t bytes = n * PlyTypeSize(prop.type);
          if (static_cast<size_t>(end - cursor) < bytes) Fail(src, "truncated binary data in " + context);
          cursor += bytes;
        } else {
          for (size_t k = 0; k < n; ++k) ascii->Next(context);
        }
      }
      if (ascii && !ascii->AtEnd()) {
        Fail(src, "line " + std::to_string(line_number) + ": too many values for " + context);
      }

      if (is_vertex) {
        Eigen::Vector3d xyz, nrm = Eigen::Vector3d::Zero();
        Eigen::Vector3f rgb = Eigen::Vector3f::Zero();
        float sigma = 0.f;
        int views = 0;
        for (size_t p = 0; p < slots.size(); ++p) {
          const double v = values[p];
          switch (slots[p]) {
            case VertexSlot::kSkip: break;
            case VertexSlot::kX: xyz.x() = v; break;
            case VertexSlot::kY: xyz.y() = v; break;
            case VertexSlot::kZ: xyz.z() = v; break;
            case VertexSlot::kNx: nrm.x() = v; break;
            case VertexSlot::kNy: nrm.y() = v; break;
            case VertexSlot::kNz: nrm.z() = v; break;
            case VertexSlot::kRed: rgb.x() = static_cast<float>(v); break;
            case VertexSlot::kGreen: rgb.y() = static_cast<float>(v); break;
            case VertexSlot::kBlue: rgb.z() = static_cast<float>(v); break;
            case VertexSlot::kSigma: sigma = static_cast<float>(v); break;
            case VertexSlot::kViews: views = static_cast<int>(v); break;
          }
        }
        if (!xyz.allFinite()) Fail(src, context + ": coordinate is not finite");
        mesh.vertices.push_back(xyz);
        if (want_normals) mesh.normals.push_back(nrm);
        if (want_colors) {
          // Colours stored as floats in 0..1 by some tools: those are scaled in one go
          // below once the whole element is known; here they are kept as read.
          mesh.colors.push_back(rgb);
        }
        if (has[int(VertexSlot::kSigma)]) mesh.sigma.push_back(sigma);
        if (has[int(VertexSlot::kViews)]) mesh.views.push_back(views);
      } else if (is_face) {
        if (list.size() < 3) continue;  // a point or a segment: no area, no triangle
        for (double index : list) {
          if (index < 0 || index >= static_cast<double>(mesh.vertices.size()) || !have_xyz) {
            Fail(src, context + ": vertex index " + std::to_string(static_cast<long long>(index)) +
                          " out of range (" + std::to_string(mesh.vertices.size()) + " vertices)");
          }
        }
        for (size_t k = 1; k + 1 < list.size(); ++k) {
          mesh.faces.emplace_back(static_cast<int>(list[0]), static_cast<int>(list[k]),
                                  static_cast<int>(list[k + 1]));
          if (face_label >= 0) mesh.face_labels.push_back(static_cast<int>(values[face_label]));
        }
      }
    }
    if (want_colors) {
      // Integer colour types are 0..255 already; float colours are 0..1 by convention.
      const PlyType red_type = [&] {
        for (size_t p = 0; p < slots.size(); ++p)
          if (slots[p] == VertexSlot::kRed) return element.properties[p].type;
        return PlyType::kUint8;
      }();
      if (!PlyTypeIsInteger(red_type)) {
        bool unit_range = true;
        for (const auto& c : mesh.colors) unit_range = unit_range && c.maxCoeff() <= 1.0f;
        if (unit_range)
          for (auto& c : mesh.colors) c *= 255.0f;
      }
    }
  }
  if (!have_xyz) Fail(src, "no vertex element");
  mesh.Check(src);
  return mesh;
}

MeshData ReadPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open PLY file");
  return ReadPly(in, path);
}

void WritePly(const std::string& path, const MeshData& mesh) {
  mesh.Check(path);
  const bool normals = !mesh.normals.empty();
  const bool colors = !mesh.colors.empty();
  const bool sigma = !mesh.sigma.empty();
  const bool views = !mesh.views.empty();
  const bool labels = !mesh.face_labels.empty();

  std::ostringstream header;
  header.imbue(std::locale::classic());
  header << "ply\nformat binary_little_endian 1.0\ncomment written by Facets\n";
  WriteFacetsComments(mesh.origin, mesh.crs, path, header);
  header << "element vertex " << mesh.vertices.size() << "\n"
         << "property double x\nproperty double y\nproperty double z\n";
  if (normals) header << "property float nx\nproperty float ny\nproperty float nz\n";
  if (colors) header << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (sigma) header << "property float sigma\n";
  if (views) header << "property int views\n";
  header << "element face " << mesh.faces.size() << "\n"
         << "property list uchar int vertex_indices\n";
  if (labels) header << "property int label\n";
  header << "end_header\n";

  std::string body;
  auto put = [&body](const auto& value) {
    const char* bytes = reinterpret_cast<const char*>(&value);
    body.append(bytes, sizeof(value));
  };
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (int c = 0; c < 3; ++c) put(mesh.vertices[i][c]);
    if (normals)
      for (int c = 0; c < 3; ++c) put(static_cast<float>(mesh.normals[i][c]));
    if (colors) {
      for (int c = 0; c < 3; ++c) {
        const float v = std::clamp(mesh.colors[i][c], 0.0f, 255.0f);
        put(static_cast<uint8_t>(std::lround(std::isfinite(v) ? v : 0.0f)));
      }
    }
    if (sigma) put(mesh.sigma[i]);
    if (views) put(static_cast<int32_t>(mesh.views[i]));
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    put(static_cast<uint8_t>(3));
    for (int c = 0; c < 3; ++c) put(static_cast<int32_t>(mesh.faces[f][c]));
    if (labels) put(static_cast<int32_t>(mesh.face_labels[f]));
  }

  WriteFileAtomically(path, header.str() + body);
}

MeshData ReadObj(std::istream& in, const std::string& source_name) {
  MeshData mesh;
  std::string line;
  size_t line_number = 0;
  std::vector<long long> polygon;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    ls.imbue(std::locale::classic());
    std::string keyword;
    ls >> keyword;
    const std::string where = source_name + ": line " + std::to_string(line_number) + ": ";
    if (keyword == "v") {
      Eigen::Vector3d p;
      if (!(ls >> p.x() >> p.y() >> p.z())) throw std::runtime_error(where + "malformed vertex");
      if (!p.allFinite()) throw std::runtime_error(where + "vertex is not finite");
      mesh.vertices.push_back(p);
    } else if (keyword == "f") {
      polygon.clear();
      std::string token;
      while (ls >> token) {
        const std::string index_text = token.substr(0, token.find('/'));
        long long index = 0;
        const auto [ptr, ec] =
            std::from_chars(index_text.data(), index_text.data() + index_text.size(), index);
        if (ec != std::errc() || ptr != index_text.data() + index_text.size() || index == 0) {
          throw std::runtime_error(where + "bad face index '" + token + "'");
        }
        const long long n = static_cast<long long>(mesh.vertices.size());
        const long long zero_based = index > 0 ? index - 1 : n + index;
        if (zero_based < 0 || zero_based >= n) {
          throw std::runtime_error(where + "face index " + std::to_string(index) +
                                   " out of range (" + std::to_string(n) + " vertices so far)");
        }
        polygon.push_back(zero_based);
      }
      if (polygon.size() < 3) throw std::runtime_error(where + "face with fewer than 3 corners");
      for (size_t k = 1; k + 1 < polygon.size(); ++k) {
        mesh.faces.emplace_back(static_cast<int>(polygon[0]), static_cast<int>(polygon[k]),
                                static_cast<int>(polygon[k + 1]));
      }
    }
  }
  if (in.bad()) throw std::runtime_error(source_name + ": read error");
  return mesh;
}

MeshData ReadObj(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open OBJ file");
  return ReadObj(in, path);
}

MeshData ReadMesh(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".ply") return ReadPly(path);
  if (ext == ".obj") return ReadObj(path);
  throw std::invalid_argument(path + ": unknown mesh format '" + ext + "' (expected .ply or .obj)");
}

}  // namespace facets
