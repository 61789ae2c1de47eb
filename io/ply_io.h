// Triangle meshes on disk: PLY (read and write) and Wavefront OBJ (read).
//
// MeshData is the plain exchange type between io/ and the stages above it: vertices in
// local object coordinates (double), triangles as vertex index triples, and optional
// per-vertex and per-face attributes. An attribute vector is either empty (absent) or
// has exactly one entry per vertex (per face).
//
// WritePly writes binary_little_endian with every attribute Facets knows, each only when
// present; ReadPly reads that back exactly and also reads ordinary PLY files of other
// tools: ascii, binary_little_endian and binary_big_endian; float or double
// coordinates; any other properties and elements skipped by their declared type; face
// lists with uchar/char/ushort/short/int/uint counts and int/uint (any integer)
// indices; polygons with more than three corners fan-triangulated (a face label is
// copied to every triangle of its polygon).
#pragma once

#include <Eigen/Core>
#include <istream>
#include <string>
#include <vector>

namespace facets {

struct MeshData {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;
  // Optional per-vertex attributes: empty, or one entry per vertex.
  std::vector<Eigen::Vector3d> normals;
  std::vector<Eigen::Vector3f> colors;  // linear 0..255
  std::vector<float> sigma;             // standard deviation of the normal displacement, m
  std::vector<int> views;               // number of images that saw the vertex
  // Optional per-face attribute: empty, or one entry per face (region label).
  std::vector<int> face_labels;
  // Where the local frame sits on the earth: global = origin + local; crs "" = unknown
  // (anything GDAL reads, e.g. "EPSG:25832"). Kept in the PLY header as the comments
  // "comment facets_origin X Y Z" and "comment facets_crs CRS", so a run's surface.ply
  // alone can be re-exported georeferenced (facets export) and other tools still read
  // the file (comments are ignored by every PLY reader).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::string crs;

  // Throws std::invalid_argument (message starts with `source_name`) when an attribute
  // vector has the wrong size or a face index is out of range.
  void Check(const std::string& source_name = "<mesh>") const;
};

// Throws std::runtime_error naming the file and what is wrong (cannot open, unknown
// format, truncated, index out of range, malformed line).
MeshData ReadPly(const std::string& path);
MeshData ReadPly(std::istream& in, const std::string& source_name = "<stream>");

// binary_little_endian, double x y z, float nx ny nz, uchar red green blue, float sigma,
// int views, face: list uchar int vertex_indices + int label. Optional attributes are
// written only when present; the origin (when not zero, exact decimals) and the crs
// (when given) as header comments. Colours are rounded and clamped to 0..255. Writes to
// a unique temporary beside path and renames it at the end: never a half-written file.
void WritePly(const std::string& path, const MeshData& mesh);

// Wavefront OBJ: "v x y z" and "f a b c ..." lines (1-based or negative relative
// indices, "a/t/n" forms accepted, polygons fan-triangulated); "vn", "vt", groups,
// materials and other lines ignored. Throws std::runtime_error naming file and line.
MeshData ReadObj(const std::string& path);
MeshData ReadObj(std::istream& in, const std::string& source_name = "<stream>");

// ReadPly for ".ply", ReadObj for ".obj" (case-insensitive); anything else throws
// std::invalid_argument naming the file.
MeshData ReadMesh(const std::string& path);

}  // namespace facets
