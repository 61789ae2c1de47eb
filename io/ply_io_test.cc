#include "io/ply_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace facets {
namespace {

std::filesystem::path TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("facets_ply_io_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

// Message of the exception thrown by `fn`, or "" when nothing was thrown.
template <typename Fn>
std::string ErrorOf(Fn fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

MeshData ExampleMesh() {
  MeshData mesh;
  // Values chosen exactly representable where the file stores float or uchar.
  mesh.vertices = {{0.1, 0.2, 0.3}, {1e6 + 0.123456789, -2.5, 3.0}, {0, 1, 1e-12}, {4, 5, 6}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  mesh.normals = {{0, 0, 1}, {0.5, 0.25, -0.125}, {1, 0, 0}, {0, -1, 0}};
  mesh.colors = {{0, 0, 0}, {255, 128, 7}, {1, 2, 3}, {200, 100, 50}};
  mesh.sigma = {0.5f, 0.001f, 1e-7f, 3.25f};
  mesh.views = {0, 2, 17, -1};
  mesh.face_labels = {3, 1};
  return mesh;
}

TEST(PlyIoTest, BinaryRoundTripIsExactForEveryAttribute) {
  const auto dir = TempDir("roundtrip");
  const std::string path = (dir / "mesh.ply").string();
  const MeshData mesh = ExampleMesh();
  WritePly(path, mesh);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  const MeshData back = ReadPly(path);
  ASSERT_EQ(back.vertices.size(), mesh.vertices.size());
  ASSERT_EQ(back.faces.size(), mesh.faces.size());
  ASSERT_EQ(back.normals.size(), mesh.normals.size());
  ASSERT_EQ(back.colors.size(), mesh.colors.size());
  ASSERT_EQ(back.sigma.size(), mesh.sigma.size());
  ASSERT_EQ(back.views.size(), mesh.views.size());
  ASSERT_EQ(back.face_labels.size(), mesh.face_labels.size());
  double max_diff = 0;
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    max_diff = std::max(max_diff, (back.vertices[i] - mesh.vertices[i]).cwiseAbs().maxCoeff());
    EXPECT_EQ(back.vertices[i], mesh.vertices[i]);
    EXPECT_EQ(back.normals[i], mesh.normals[i]);
    EXPECT_EQ(back.colors[i], mesh.colors[i]);
    EXPECT_EQ(back.sigma[i], mesh.sigma[i]);
    EXPECT_EQ(back.views[i], mesh.views[i]);
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    EXPECT_EQ(back.faces[f], mesh.faces[f]);
    EXPECT_EQ(back.face_labels[f], mesh.face_labels[f]);
  }
  std::cout << "round trip: " << back.vertices.size() << " vertices, " << back.faces.size()
            << " faces, max coordinate difference " << max_diff << " m, file size "
            << std::filesystem::file_size(path) << " bytes\n";
  std::filesystem::remove_all(dir);
}

// Issue 8 round trip with UTM-sized coordinates: a surface around (500000, 5400000,
// 300) in local coordinates with that origin and a CRS. The file keeps the local
// doubles and the origin (header comment, exact decimals), so adding the origin back
// gives the global positions; the bound is 1 mm, the result is exact.
TEST(PlyIoTest, UtmOriginAndCrsRoundTrip) {
  const auto dir = TempDir("utm");
  const std::string path = (dir / "surface.ply").string();
  MeshData mesh;
  mesh.origin = Eigen::Vector3d(500000.0, 5400000.0, 300.0);
  mesh.crs = "EPSG:25832";
  std::vector<Eigen::Vector3d> global;
  for (int j = 0; j < 30; ++j) {
    for (int i = 0; i < 40; ++i) {
      // Global positions with sub-millimetre decimals, 0.37 m apart, up to ~15 m from the origin.
      global.emplace_back(500000.0 + 0.37 * i - 7.123456, 5400000.0 + 0.37 * j - 5.654321,
                          300.0 + std::sin(0.2 * i) * std::cos(0.3 * j) + 0.0001234);
      mesh.vertices.push_back(global.back() - mesh.origin);
    }
  }
  for (int j = 0; j + 1 < 30; ++j) {
    for (int i = 0; i + 1 < 40; ++i) {
      const int a = j * 40 + i;
      mesh.faces.emplace_back(a, a + 1, a + 41);
      mesh.faces.emplace_back(a, a + 41, a + 40);
    }
  }
  WritePly(path, mesh);
  const MeshData back = ReadPly(path);
  ASSERT_EQ(back.vertices.size(), mesh.vertices.size());
  EXPECT_EQ(back.faces, mesh.faces);
  EXPECT_EQ(back.origin, mesh.origin);
  EXPECT_EQ(back.crs, mesh.crs);
  double max_error = 0;
  for (size_t i = 0; i < global.size(); ++i) {
    max_error = std::max(max_error, (back.origin + back.vertices[i] - global[i]).norm());
  }
  std::cout << "UTM round trip: " << back.vertices.size() << " vertices, origin "
            << back.origin.transpose() << ", max global position error " << max_error << " m\n";
  EXPECT_LT(max_error, 1e-3);

  // A file without the comments (another tool's) reads with origin zero and no CRS; a
  // malformed origin comment is an error naming the file.
  std::istringstream plain("ply\nformat ascii 1.0\ncomment other tool\nelement vertex 1\n"
                           "property float x\nproperty float y\nproperty float z\n"
                           "end_header\n1 2 3\n");
  const MeshData other = ReadPly(plain, "other.ply");
  EXPECT_EQ(other.origin, Eigen::Vector3d::Zero());
  EXPECT_EQ(other.crs, "");
  std::istringstream bad("ply\nformat ascii 1.0\ncomment facets_origin 1 2\nelement vertex 0\n"
                         "property float x\nproperty float y\nproperty float z\nend_header\n");
  const std::string message = ErrorOf([&] { ReadPly(bad, "bad.ply"); });
  EXPECT_NE(message.find("bad.ply"), std::string::npos) << message;
  EXPECT_NE(message.find("facets_origin"), std::string::npos) << message;
  std::filesystem::remove_all(dir);
}

TEST(PlyIoTest, OptionalAttributesAbsentStayAbsent) {
  const auto dir = TempDir("plain");
  const std::string path = (dir / "plain.ply").string();
  MeshData mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.faces = {{0, 1, 2}};
  WritePly(path, mesh);
  const MeshData back = ReadPly(path);
  EXPECT_EQ(back.vertices.size(), 3u);
  EXPECT_EQ(back.faces.size(), 1u);
  EXPECT_TRUE(back.normals.empty());
  EXPECT_TRUE(back.colors.empty());
  EXPECT_TRUE(back.sigma.empty());
  EXPECT_TRUE(back.views.empty());
  EXPECT_TRUE(back.face_labels.empty());
  std::filesystem::remove_all(dir);
}

TEST(PlyIoTest, AsciiWithExtraPropertiesQuadsAndOtherElements) {
  // Float coordinates, an unknown per-vertex property, an unknown list property, an
  // extra element, a quad, uint list counts, CRLF line endings and comments.
  const std::string text =
      "ply\r\n"
      "format ascii 1.0\r\n"
      "comment made by another tool\r\n"
      "element vertex 5\r\n"
      "property float x\r\nproperty float y\r\nproperty float z\r\n"
      "property float confidence\r\n"
      "property list uchar float texcoord\r\n"
      "property uchar red\r\nproperty uchar green\r\nproperty uchar blue\r\n"
      "element face 2\r\n"
      "property list uint int vertex_indices\r\n"
      "property int label\r\n"
      "element edge 1\r\n"
      "property int vertex1\r\nproperty int vertex2\r\n"
      "end_header\r\n"
      "0 0 0 0.9 2 0.5 0.5 10 20 30\r\n"
      "1 0 0 0.8 0 11 21 31\r\n"
      "1 1 0 0.7 2 1 1 12 22 32\r\n"
      "0 1 0 0.6 0 13 23 33\r\n"
      "+0.5 0.5 1e0 0.5 0 14 24 34\r\n"
      "4 0 1 2 3 2\r\n"
      "3 0 1 4 1\r\n"
      "\r\n"
      "0 1\r\n";
  std::istringstream in(text);
  const MeshData mesh = ReadPly(in, "ascii.ply");
  ASSERT_EQ(mesh.vertices.size(), 5u);
  ASSERT_EQ(mesh.faces.size(), 3u);  // quad -> 2 triangles, plus one triangle
  EXPECT_EQ(mesh.faces[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(mesh.faces[1], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(mesh.faces[2], Eigen::Vector3i(0, 1, 4));
  EXPECT_EQ(mesh.face_labels, (std::vector<int>{2, 2, 1}));
  EXPECT_EQ(mesh.vertices[4], Eigen::Vector3d(0.5, 0.5, 1.0));
  ASSERT_EQ(mesh.colors.size(), 5u);
  EXPECT_EQ(mesh.colors[2], Eigen::Vector3f(12, 22, 32));
  EXPECT_TRUE(mesh.normals.empty());
  std::cout << "ascii: " << mesh.vertices.size() << " vertices, " << mesh.faces.size()
            << " triangles\n";
}

TEST(PlyIoTest, BinaryBigEndianFloatCoordinates) {
  std::string data =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\n"
      "property float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar uint vertex_indices\nend_header\n";
  auto put_be = [&data](const auto& value) {
    const char* bytes = reinterpret_cast<const char*>(&value);
    for (int i = sizeof(value) - 1; i >= 0; --i) data.push_back(bytes[i]);
  };
  const float xyz[3][3] = {{0, 0, 0}, {2.5f, 0, 0}, {0, -1.25f, 7}};
  for (const auto& p : xyz)
    for (float c : p) put_be(c);
  data.push_back(3);
  for (uint32_t i : {0u, 1u, 2u}) put_be(i);
  std::istringstream in(data);
  const MeshData mesh = ReadPly(in, "big.ply");
  ASSERT_EQ(mesh.vertices.size(), 3u);
  ASSERT_EQ(mesh.faces.size(), 1u);
  EXPECT_EQ(mesh.vertices[1], Eigen::Vector3d(2.5, 0, 0));
  EXPECT_EQ(mesh.vertices[2], Eigen::Vector3d(0, -1.25, 7));
  EXPECT_EQ(mesh.faces[0], Eigen::Vector3i(0, 1, 2));
}

TEST(PlyIoTest, MalformedInputsThrowNamingFileAndProblem) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  struct Case {
    std::string name;
    std::string text;
    std::string expected;  // part of the message
  };
  const std::vector<Case> cases = {
      {"not_ply", "solid cube\n", "not a PLY file"},
      {"unknown_format", "ply\nformat binary_middle_endian 1.0\nend_header\n",
       "unknown PLY format"},
      {"no_end_header", "ply\nformat ascii 1.0\nelement vertex 1\n", "no end_header"},
      {"unknown_type", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
       "unknown property type"},
      {"truncated_ascii", header + "0 0 0\n1 0 0\n", "truncated"},
      {"index_out_of_range", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "out of range"},
      {"not_a_number", header + "0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", "line 11"},
      {"too_few_values", header + "0 0 0\n1 0\n0 1 0\n3 0 1 2\n", "too few values"},
      {"nan_vertex", header + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "not finite"},
      {"truncated_binary",
       "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\n"
       "property double y\nproperty double z\nend_header\n" +
           std::string(30, '\0'),
       "need at least 48 bytes of data, but only 30 bytes follow the header"},
      {"huge_count",
       "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\n"
       "property float y\nproperty float z\nend_header\n" +
           std::string(12, '\0'),
       "(1000000000 vertex) need at least 12000000000 bytes"},
      {"huge_ascii_count",
       "ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\n"
       "property float y\nproperty float z\nend_header\n0 0 0\n",
       "need at least 6000000000 bytes"},
      {"list_past_end", header + "0 0 0\n1 0 0\n0 1 0\n200 0 1 2\n",
       "face 0: bad list length 200 (the data left holds 3)"},
      {"truncated_list",
       "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n"
       "property float y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\n"
       "end_header\n" +
           std::string("\x03\0\0\0\0\0\0\0", 8),
       "face 0: bad list length 3 (the data left holds 1)"},
  };
  for (const Case& c : cases) {
    std::istringstream in(c.text);
    const std::string message = ErrorOf([&] { ReadPly(in, c.name + ".ply"); });
    std::cout << c.name << ": " << message << "\n";
    EXPECT_NE(message.find(c.name + ".ply"), std::string::npos) << message;
    EXPECT_NE(message.find(c.expected), std::string::npos) << message;
  }
  const std::string missing = ErrorOf([] { ReadPly("/nonexistent/dir/mesh.ply"); });
  EXPECT_NE(missing.find("/nonexistent/dir/mesh.ply"), std::string::npos) << missing;
}

// An element without properties takes no bytes whatever its count: it is passed over at
// once, not walked instance by instance.
TEST(PlyIoTest, ElementWithoutPropertiesIsPassedOver) {
  std::istringstream in(
      "ply\nformat binary_little_endian 1.0\nelement nothing 1000000000000000\n"
      "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n" +
      std::string(12, '\0'));
  const MeshData mesh = ReadPly(in, "nothing.ply");
  EXPECT_EQ(mesh.vertices.size(), 1u);
}

// Counts and values the data cannot back (found by fuzz/ply_fuzzer.cc): each is an error
// naming the file, never an allocation of the header's count, a hang or an undefined
// conversion to int.
TEST(PlyIoTest, CountsAndValuesBeyondTheDataAreErrors) {
  const std::string ascii = "ply\nformat ascii 1.0\n";
  const std::string binary = "ply\nformat binary_little_endian 1.0\n";
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  const std::string face = "element face 1\nproperty list uchar int vertex_indices\n";
  const std::string three = "0 0 0\n1 0 0\n0 1 0\n";
  const std::string floats(36, '\0');  // three binary vertices at the origin
  struct Case {
    std::string name, text, expected;
  };
  const std::vector<Case> cases = {
      // Reserving 10^12 vertices (24 TB) was attempted before the data was read.
      {"ascii_vertex_count", ascii + "element vertex 1000000000000\n" + xyz + "end_header\n" + three,
       "header counts (1000000000000 vertex) need at least 6000000000000 bytes of data, but only 18 bytes"},
      {"binary_vertex_count", binary + "element vertex 4000000000\n" + xyz + "end_header\n" + floats,
       "header counts (4000000000 vertex) need at least 48000000000 bytes of data, but only 36 bytes"},
      // A list count of 4e9 resized the face's index list to 32 GB.
      {"binary_list_length",
       binary + "element vertex 3\n" + xyz + "element face 1\nproperty list uint int vertex_indices\n" +
           "end_header\n" + floats + std::string("\x00\x28\x6b\xee", 4) + std::string(12, '\0'),
       "face 0: bad list length 4e+09 (the data left holds 3)"},
      {"ascii_list_length", ascii + "element vertex 3\n" + xyz + face + "end_header\n" + three + "1e300 0 1 2\n",
       "face 0: bad list length 1e+300 (the data left holds 3)"},
      {"views_range", ascii + "element vertex 3\n" + xyz + "property int views\nend_header\n" +
                          "0 0 0 1\n1 0 0 1e10\n0 1 0 1\n",
       "vertex 1: views 1e+10 is out of range"},
      {"label_range", ascii + "element vertex 3\n" + xyz + face + "property int label\nend_header\n" + three +
                          "3 0 1 2 nan\n",
       "face 0: label nan is out of range"},
      // Two vertex elements, one with normals: MeshData::Check threw std::invalid_argument.
      {"second_vertex", ascii + "element vertex 1\n" + xyz + "element vertex 1\n" + xyz +
                            "property float nx\nproperty float ny\nproperty float nz\nend_header\n",
       "line 7: a second 'vertex' element"},
      {"nan_index", ascii + "element vertex 3\n" + xyz + face + "end_header\n" + three + "3 0 nan 2\n",
       "face 0: vertex index nan out of range (3 vertices)"},
  };
  for (const Case& c : cases) {
    std::istringstream in(c.text);
    const std::string message = ErrorOf([&] { ReadPly(in, c.name + ".ply"); });
    EXPECT_EQ(message.rfind(c.name + ".ply: ", 0), 0u) << message;
    EXPECT_NE(message.find(c.expected), std::string::npos) << message;
  }
  // Instances without properties hold no data: 10^18 of them are read at once.
  std::istringstream empty_elements(binary + "element marker 1000000000000000000\nelement vertex 3\n" + xyz +
                                    "end_header\n" + floats);
  EXPECT_EQ(ReadPly(empty_elements, "marker.ply").vertices.size(), 3u);
}

TEST(PlyIoTest, WriterRejectsInconsistentMesh) {
  const auto dir = TempDir("bad");
  MeshData mesh = ExampleMesh();
  mesh.sigma.pop_back();
  const std::string path = (dir / "bad.ply").string();
  EXPECT_THROW(WritePly(path, mesh), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  std::filesystem::remove_all(dir);
}

TEST(ObjIoTest, ReadsVerticesAndPolygonFaces) {
  const std::string text =
      "# cube corner\nmtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\n"
      "g top\nf 1/1/1 2/2/1 3/3/1 4/4/1\nf -4 -3 -2\n";
  std::istringstream in(text);
  const MeshData mesh = ReadObj(in, "quad.obj");
  ASSERT_EQ(mesh.vertices.size(), 4u);
  ASSERT_EQ(mesh.faces.size(), 3u);
  EXPECT_EQ(mesh.faces[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(mesh.faces[1], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(mesh.faces[2], Eigen::Vector3i(0, 1, 2));

  std::istringstream bad("v 0 0 0\nv 1 0 0\nf 1 2 5\n");
  const std::string message = ErrorOf([&] { ReadObj(bad, "bad.obj"); });
  std::cout << "obj error: " << message << "\n";
  EXPECT_NE(message.find("bad.obj: line 3"), std::string::npos) << message;
  EXPECT_THROW(ReadMesh("/tmp/mesh.stl"), std::invalid_argument);
}

}  // namespace
}  // namespace facets
