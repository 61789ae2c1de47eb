#include "io/ply_io.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <locale>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "io/atomic_file.h"
#include "io/input_file.h"

namespace facets {

static_assert(std::endian::native == std::endian::little,
              "WritePly assumes a little-endian host");

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
  std::ifstream in = OpenInputFile(path, "OBJ file");
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
