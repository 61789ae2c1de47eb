// ReadPly: the PLY header, then every element of the body (ascii or binary, either
// byte order) into MeshData; see io/ply_io.h for what is read.
#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <locale>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "io/input_file.h"
#include "io/ply_io.h"
#include "io/ply_values.h"

namespace facets {
namespace {

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

// "comment facets_origin X Y Z" / "comment facets_crs CRS" (see MeshData::origin); any
// other comment is ignored.
void ReadFacetsComment(std::istringstream& ls, const std::string& src, const std::string& where,
                       Eigen::Vector3d* origin, std::string* crs) {
  std::string key;
  ls >> key;
  if (key == "facets_origin") {
    for (int c = 0; c < 3; ++c) ls >> (*origin)[c];
    if (!ls || !origin->allFinite()) FailPly(src, where + "malformed facets_origin comment");
  } else if (key == "facets_crs") {
    std::getline(ls >> std::ws, *crs);
    if (crs->empty()) FailPly(src, where + "empty facets_crs comment");
  }
}

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::string crs;
  std::vector<PlyElement> elements;
};

// The fewest bytes the body after `header` can take: binary, every scalar and list count
// at its type's size with all lists empty; ascii, 2 bytes per value (a digit and a
// separator). Saturates at ULLONG_MAX instead of overflowing. Checked against the file
// before anything is allocated, so a short file cannot claim 10^9 vertices.
unsigned long long MinimumBodyBytes(const PlyHeader& header) {
  const bool binary = header.format != PlyFormat::kAscii;
  unsigned long long total = 0;
  for (const PlyElement& element : header.elements) {
    unsigned long long record = 0;
    for (const PlyProperty& p : element.properties) {
      record += binary ? PlyTypeSize(p.is_list ? p.count_type : p.type) : 2;
    }
    if (element.count > (ULLONG_MAX - total) / std::max(record, 1ULL)) return ULLONG_MAX;
    total += element.count * record;
  }
  return total;
}

std::string CountsText(const PlyHeader& header) {
  std::string text;
  for (const PlyElement& element : header.elements) {
    text += (text.empty() ? "" : ", ") + std::to_string(element.count) + " " + element.name;
  }
  return text;
}

// What the reader does with one element's properties: the MeshData field of each
// vertex property, or the face's vertex list and label.
struct ElementLayout {
  bool is_vertex = false;
  bool is_face = false;
  std::vector<VertexSlot> slots;  // per property; kSkip unless a vertex scalar
  bool has[12] = {};              // per VertexSlot: the vertex element has it
  int face_list = -1;             // property index of the face's vertex indices
  int face_label = -1;            // property index of the face's label, -1: none
  bool want_normals = false;
  bool want_colors = false;

  bool Has(VertexSlot slot) const { return has[static_cast<int>(slot)]; }
};

ElementLayout LayoutOf(const PlyElement& element, const std::string& src) {
  ElementLayout layout;
  layout.is_vertex = element.name == "vertex";
  layout.is_face = element.name == "face";
  layout.slots.assign(element.properties.size(), VertexSlot::kSkip);
  if (layout.is_vertex) {
    for (size_t p = 0; p < element.properties.size(); ++p) {
      if (element.properties[p].is_list) continue;
      layout.slots[p] = VertexSlotOf(element.properties[p].name);
      layout.has[static_cast<int>(layout.slots[p])] = true;
    }
    if (!layout.Has(VertexSlot::kX) || !layout.Has(VertexSlot::kY) ||
        !layout.Has(VertexSlot::kZ)) {
      FailPly(src, "vertex element lacks x, y or z");
    }
    layout.want_normals = layout.Has(VertexSlot::kNx) && layout.Has(VertexSlot::kNy) &&
                          layout.Has(VertexSlot::kNz);
    layout.want_colors = layout.Has(VertexSlot::kRed) && layout.Has(VertexSlot::kGreen) &&
                         layout.Has(VertexSlot::kBlue);
  }
  if (layout.is_face) {
    for (size_t p = 0; p < element.properties.size(); ++p) {
      const PlyProperty& prop = element.properties[p];
      if (prop.is_list && (prop.name == "vertex_indices" || prop.name == "vertex_index")) {
        if (!PlyTypeIsInteger(prop.type)) FailPly(src, "face vertex indices are not integers");
        layout.face_list = static_cast<int>(p);
      } else if (!prop.is_list && (prop.name == "label" || prop.name == "region")) {
        layout.face_label = static_cast<int>(p);
      }
    }
    if (layout.face_list < 0) FailPly(src, "face element has no vertex_indices list");
  }
  return layout;
}

PlyFormat PlyFormatFromName(const std::string& name, const std::string& src,
                            const std::string& where) {
  if (name == "ascii") return PlyFormat::kAscii;
  if (name == "binary_little_endian") return PlyFormat::kBinaryLittle;
  if (name == "binary_big_endian") return PlyFormat::kBinaryBig;
  FailPly(src, where + "unknown PLY format '" + name + "'");
}

// "property TYPE NAME" or "property list COUNT_TYPE ITEM_TYPE NAME" after the keyword.
PlyProperty ParseProperty(std::istringstream& ls, const std::string& line, const std::string& src,
                          const std::string& where) {
  PlyProperty property;
  std::string type_name;
  ls >> type_name;
  if (type_name == "list") {
    std::string count_name, item_name;
    ls >> count_name >> item_name >> property.name;
    if (!ls) FailPly(src, where + "malformed list property '" + line + "'");
    if (!PlyTypeFromName(count_name, &property.count_type) ||
        !PlyTypeIsInteger(property.count_type)) {
      FailPly(src, where + "bad list count type '" + count_name + "'");
    }
    if (!PlyTypeFromName(item_name, &property.type)) {
      FailPly(src, where + "unknown property type '" + item_name + "'");
    }
    property.is_list = true;
  } else {
    ls >> property.name;
    if (!ls) FailPly(src, where + "malformed property line '" + line + "'");
    if (!PlyTypeFromName(type_name, &property.type)) {
      FailPly(src, where + "unknown property type '" + type_name + "'");
    }
  }
  return property;
}

// Reads a PLY stream: the header, then every element in order, filling a MeshData.
class PlyReader {
 public:
  PlyReader(std::istream& in, const std::string& source) : in_(in), src_(source) {}

  MeshData Read() {
    if (!NextLine() || Trim(line_) != "ply") {
      FailPly(src_, "not a PLY file (first line is not 'ply')");
    }
    const PlyHeader header = ReadHeader();
    mesh_.origin = header.origin;
    mesh_.crs = header.crs;
    binary_ = header.format != PlyFormat::kAscii;
    swap_ = header.format == PlyFormat::kBinaryBig;
    data_.assign(std::istreambuf_iterator<char>(in_), std::istreambuf_iterator<char>());
    if (in_.bad()) FailPly(src_, "read error after the header");
    cursor_ = data_.data();
    end_ = data_.data() + data_.size();
    in_body_ = true;
    const unsigned long long needed = MinimumBodyBytes(header);
    if (needed > data_.size() + (binary_ ? 0 : 1)) {  // ascii: the last value needs no separator
      FailPly(src_, "header counts (" + CountsText(header) + ") need at least " +
                     (needed == ULLONG_MAX ? std::string("2^64") : std::to_string(needed)) +
                     " bytes of data, but only " + std::to_string(data_.size()) +
                     " bytes follow the header (truncated file or wrong counts)");
    }
    for (const PlyElement& element : header.elements) ReadElement(element);
    if (!have_xyz_) FailPly(src_, "no vertex element");
    mesh_.Check(src_);
    return std::move(mesh_);
  }

 private:
  // The next line into line_ without a trailing '\r'; false at the end of the stream.
  bool NextLine() {
    if (!in_body_) {
      if (!std::getline(in_, line_)) return false;
    } else {
      if (cursor_ >= end_) return false;
      const char* newline = std::find(cursor_, end_, '\n');
      line_.assign(cursor_, newline);
      cursor_ = newline == end_ ? end_ : newline + 1;
    }
    ++line_number_;
    if (!line_.empty() && line_.back() == '\r') line_.pop_back();
    return true;
  }

  PlyHeader ReadHeader() {
    PlyHeader header;
    bool have_format = false;
    bool header_done = false;
    while (NextLine()) {
      std::istringstream ls(line_);
      ls.imbue(std::locale::classic());
      std::string keyword;
      ls >> keyword;
      const std::string where = "line " + std::to_string(line_number_) + ": ";
      if (keyword == "comment") {
        ReadFacetsComment(ls, src_, where, &header.origin, &header.crs);
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
        header.format = PlyFormatFromName(name, src_, where);
        have_format = true;
      } else if (keyword == "element") {
        header.elements.push_back(ParseElement(ls, where));
        // One vertex and one face element: a second one would mix attribute sets.
        const std::string& name = header.elements.back().name;
        const auto same = [&name](const PlyElement& e) { return e.name == name; };
        if ((name == "vertex" || name == "face") &&
            std::count_if(header.elements.begin(), header.elements.end(), same) > 1) {
          FailPly(src_, where + "a second '" + name + "' element");
        }
      } else if (keyword == "property") {
        if (header.elements.empty()) FailPly(src_, where + "property before any element");
        header.elements.back().properties.push_back(ParseProperty(ls, line_, src_, where));
      } else {
        FailPly(src_, where + "unknown header keyword '" + keyword + "'");
      }
    }
    if (!header_done) FailPly(src_, "truncated header (no end_header)");
    if (!have_format) FailPly(src_, "header has no format line");
    return header;
  }

  // "element NAME COUNT" after the keyword.
  PlyElement ParseElement(std::istringstream& ls, const std::string& where) {
    PlyElement element;
    long long count = -1;
    ls >> element.name >> count;
    if (!ls || count < 0) FailPly(src_, where + "malformed element line '" + line_ + "'");
    element.count = static_cast<size_t>(count);
    return element;
  }

  void ReadElement(const PlyElement& element) {
    const ElementLayout layout = LayoutOf(element, src_);
    if (binary_ && element.properties.empty()) return;  // instances of nothing: no data
    if (layout.is_vertex) {
      have_xyz_ = true;
      const size_t reserve = std::min(element.count, PlausibleCount(element));
      mesh_.vertices.reserve(reserve);
      if (layout.want_normals) mesh_.normals.reserve(reserve);
    }
    for (size_t i = 0; i < element.count; ++i) {
      const std::string context = element.name + " " + std::to_string(i);
      ReadInstance(element, layout, i, context);
      if (layout.is_vertex) {
        StoreVertex(layout, context);
      } else if (layout.is_face) {
        StoreFace(layout, context);
      }
    }
    if (layout.want_colors) ScaleUnitColors(element, layout);
  }

  // How many instances of `element` the data can hold (reserved, whatever the header
  // says): binary, the bytes left over the instance's scalars and list counts; an ascii
  // body is not read ahead: kAsciiReserve.
  size_t PlausibleCount(const PlyElement& element) const {
    if (!binary_) return kAsciiReserve;
    size_t min_bytes = 0;
    for (const PlyProperty& p : element.properties) min_bytes += PlyTypeSize(p.is_list ? p.count_type : p.type);
    return static_cast<size_t>(end_ - cursor_) / std::max<size_t>(min_bytes, 1);
  }

  // The length of a list as read: a whole number the rest of the data can hold (in
  // binary, n items of `type`; in ascii, n values on the rest of the line).
  size_t ListLength(double count, PlyType type, const std::optional<PlyAsciiLine>& ascii,
                    const std::string& context) const {
    const double fits = binary_ ? static_cast<double>(end_ - cursor_) / static_cast<double>(PlyTypeSize(type))
                                : static_cast<double>(ascii->Left());
    if (!(count >= 0 && count == std::floor(count) && count <= fits)) {
      FailPly(src_, context + ": bad list length " + FormatPlyNumber(count) + " (the data left holds " +
                     FormatPlyNumber(std::floor(fits)) + ")");
    }
    return static_cast<size_t>(count);
  }

  // Reads instance i of `element`: its scalars into values_ (in property order) and the
  // face's vertex list into list_; other lists are skipped.
  void ReadInstance(const PlyElement& element, const ElementLayout& layout, size_t i,
                    const std::string& context) {
    std::optional<PlyAsciiLine> ascii;
    if (!binary_) {
      do {
        if (!NextLine()) {
          FailPly(src_, "truncated ascii data: expected " + std::to_string(element.count) + " " +
                         element.name + " lines, found " + std::to_string(i));
        }
      } while (Trim(line_).empty());
      ascii.emplace(line_, src_, line_number_);
    }
    values_.assign(element.properties.size(), 0.0);
    for (size_t p = 0; p < element.properties.size(); ++p) {
      const PlyProperty& prop = element.properties[p];
      if (!prop.is_list) {
        values_[p] = ReadScalar(prop.type, ascii, context);
        continue;
      }
      const size_t n = ListLength(ReadScalar(prop.count_type, ascii, context), prop.type, ascii, context);
      if (layout.is_face && static_cast<int>(p) == layout.face_list) {
        list_.resize(n);
        for (size_t k = 0; k < n; ++k) list_[k] = ReadScalar(prop.type, ascii, context);
      } else {
        SkipList(prop.type, n, ascii, context);
      }
    }
    if (ascii && !ascii->AtEnd()) {
      FailPly(src_, "line " + std::to_string(line_number_) + ": too many values for " + context);
    }
  }

  double ReadScalar(PlyType type, std::optional<PlyAsciiLine>& ascii, const std::string& context) {
    return binary_ ? ReadBinaryScalar(&cursor_, end_, type, swap_, src_, context)
                   : ascii->Next(context);
  }

  void SkipList(PlyType type, size_t n, std::optional<PlyAsciiLine>& ascii,
                const std::string& context) {
    if (binary_) {
      const size_t bytes = n * PlyTypeSize(type);
      if (static_cast<size_t>(end_ - cursor_) < bytes) {
        FailPly(src_, "truncated binary data in " + context);
      }
      cursor_ += bytes;
    } else {
      for (size_t k = 0; k < n; ++k) ascii->Next(context);
    }
  }

  void StoreVertex(const ElementLayout& layout, const std::string& context) {
    Eigen::Vector3d xyz, nrm = Eigen::Vector3d::Zero();
    Eigen::Vector3f rgb = Eigen::Vector3f::Zero();
    float sigma = 0.f;
    int views = 0;
    for (size_t p = 0; p < layout.slots.size(); ++p) {
      const double v = values_[p];
      switch (layout.slots[p]) {
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
        case VertexSlot::kViews: views = IntValue(v, context, "views"); break;
      }
    }
    if (!xyz.allFinite()) FailPly(src_, context + ": coordinate is not finite");
    mesh_.vertices.push_back(xyz);
    if (layout.want_normals) mesh_.normals.push_back(nrm);
    // Colours stored as floats in 0..1 by some tools are scaled in one go once the whole
    // element is known (ScaleUnitColors); here they are kept as read.
    if (layout.want_colors) mesh_.colors.push_back(rgb);
    if (layout.Has(VertexSlot::kSigma)) mesh_.sigma.push_back(sigma);
    if (layout.Has(VertexSlot::kViews)) mesh_.views.push_back(views);
  }

  // The polygon in list_ fan-triangulated; its label (if any) copied to every triangle.
  void StoreFace(const ElementLayout& layout, const std::string& context) {
    if (list_.size() < 3) return;  // a point or a segment: no area, no triangle
    for (double index : list_) {
      if (!(index >= 0 && index < static_cast<double>(mesh_.vertices.size())) || !have_xyz_) {
        FailPly(src_, context + ": vertex index " + FormatPlyNumber(index) + " out of range (" +
                       std::to_string(mesh_.vertices.size()) + " vertices)");
      }
    }
    const int label = layout.face_label >= 0 ? IntValue(values_[layout.face_label], context, "label") : 0;
    for (size_t k = 1; k + 1 < list_.size(); ++k) {
      mesh_.faces.emplace_back(static_cast<int>(list_[0]), static_cast<int>(list_[k]),
                               static_cast<int>(list_[k + 1]));
      if (layout.face_label >= 0) mesh_.face_labels.push_back(label);
    }
  }

  // Integer colour types are 0..255 already; float colours are 0..1 by convention, and
  // are scaled to 0..255 when every colour read lies within 0..1.
  void ScaleUnitColors(const PlyElement& element, const ElementLayout& layout) {
    PlyType red_type = PlyType::kUint8;
    for (size_t p = 0; p < layout.slots.size(); ++p) {
      if (layout.slots[p] == VertexSlot::kRed) {
        red_type = element.properties[p].type;
        break;
      }
    }
    if (PlyTypeIsInteger(red_type)) return;
    bool unit_range = true;
    for (const auto& c : mesh_.colors) unit_range = unit_range && c.maxCoeff() <= 1.0f;
    if (unit_range) {
      for (auto& c : mesh_.colors) c *= 255.0f;
    }
  }

  // An integer property (views, label) as int; values outside int's range are an error.
  int IntValue(double value, const std::string& context, const std::string& what) const {
    if (value >= INT32_MIN && value <= INT32_MAX) return static_cast<int>(value);
    FailPly(src_, context + ": " + what + " " + FormatPlyNumber(value) + " is out of range");
  }

  static constexpr size_t kAsciiReserve = size_t{1} << 16;

  std::istream& in_;
  const std::string& src_;
  std::string line_;
  size_t line_number_ = 0;
  bool binary_ = false;
  bool swap_ = false;
  bool in_body_ = false;             // lines come from data_, no longer from in_
  std::string data_;  // the body after the header, read whole
  const char* cursor_ = nullptr;
  const char* end_ = nullptr;
  MeshData mesh_;
  bool have_xyz_ = false;       // a vertex element with x, y and z was read
  std::vector<double> values_;  // one element instance, scalars in property order
  std::vector<double> list_;    // the face's vertex list of the current instance
};

}  // namespace

MeshData ReadPly(std::istream& in, const std::string& source_name) {
  return PlyReader(in, source_name).Read();
}

MeshData ReadPly(const std::string& path) {
  std::ifstream in = OpenInputFile(path, "PLY file");
  return ReadPly(in, path);
}

}  // namespace facets
