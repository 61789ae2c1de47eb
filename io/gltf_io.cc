#include "io/gltf_io.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "io/atomic_file.h"

namespace facets {
namespace {

constexpr int kMax16BitVertices = 65535;  // indices 0..65534; 65535 = primitive restart

// Appends raw bytes as a new bufferView (4-byte aligned) and returns its index.
int AddBufferView(tinygltf::Model* model, const void* data, size_t bytes, int target) {
  std::vector<unsigned char>& buffer = model->buffers[0].data;
  while (buffer.size() % 4 != 0) buffer.push_back(0);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = buffer.size();
  view.byteLength = bytes;
  view.target = target;
  const auto* p = static_cast<const unsigned char*>(data);
  buffer.insert(buffer.end(), p, p + bytes);
  model->bufferViews.push_back(view);
  return static_cast<int>(model->bufferViews.size()) - 1;
}

template <typename T>
int AddAccessor(tinygltf::Model* model, const std::vector<T>& values, int components,
                int component_type, int type, int target, bool with_min_max = false) {
  tinygltf::Accessor accessor;
  accessor.bufferView = AddBufferView(model, values.data(), values.size() * sizeof(T), target);
  accessor.byteOffset = 0;
  accessor.componentType = component_type;
  accessor.count = values.size() / components;
  accessor.type = type;
  if (with_min_max) {
    accessor.minValues.assign(components, std::numeric_limits<double>::infinity());
    accessor.maxValues.assign(components, -std::numeric_limits<double>::infinity());
    for (size_t i = 0; i < values.size(); ++i) {
      const int c = static_cast<int>(i % components);
      accessor.minValues[c] = std::min(accessor.minValues[c], static_cast<double>(values[i]));
      accessor.maxValues[c] = std::max(accessor.maxValues[c], static_cast<double>(values[i]));
    }
  }
  model->accessors.push_back(accessor);
  return static_cast<int>(model->accessors.size()) - 1;
}

tinygltf::Value GeoreferenceExtras(const ExportSurface& surface) {
  tinygltf::Value::Object facets;
  facets["origin"] = tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(surface.origin.x()),
                                                            tinygltf::Value(surface.origin.y()),
                                                            tinygltf::Value(surface.origin.z())});
  facets["crs"] = tinygltf::Value(surface.crs);
  facets["up"] = tinygltf::Value(std::string("Z"));
  facets["units"] = tinygltf::Value(std::string("m"));
  tinygltf::Value::Object extras;
  extras["facets"] = tinygltf::Value(std::move(facets));
  return tinygltf::Value(std::move(extras));
}

// One primitive's share of the surface: `source` lists, per primitive vertex, the
// surface vertex it copies and (textured) the triangle corner 3 t + k it stands for.
struct Chunk {
  std::vector<int> vertex;  // surface vertex per primitive vertex
  std::vector<int> corner;  // triangle corner per primitive vertex (textured only)
  std::vector<uint32_t> indices;
};

std::vector<Chunk> SplitIntoChunks(const ExportSurface& surface, bool per_corner,
                                   int max_vertices) {
  std::vector<Chunk> chunks(1);
  const size_t limit =
      max_vertices > 0 ? static_cast<size_t>(max_vertices) : std::numeric_limits<size_t>::max();
  std::vector<int> stamp(surface.vertices.size(), -1);  // chunk that holds the vertex
  std::vector<uint32_t> local(surface.vertices.size(), 0);
  for (size_t t = 0; t < surface.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = surface.triangles[t];
    const int current = static_cast<int>(chunks.size()) - 1;
    size_t added = 3;
    if (!per_corner) {
      added = 0;
      for (int k = 0; k < 3; ++k) {
        bool repeated = false;
        for (int m = 0; m < k; ++m) repeated = repeated || tri[m] == tri[k];
        if (stamp[tri[k]] != current && !repeated) ++added;
      }
    }
    if (chunks.back().vertex.size() + added > limit) chunks.emplace_back();
    Chunk& chunk = chunks.back();
    const int id = static_cast<int>(chunks.size()) - 1;
    for (int k = 0; k < 3; ++k) {
      const int v = tri[k];
      if (per_corner) {
        chunk.indices.push_back(static_cast<uint32_t>(chunk.vertex.size()));
        chunk.vertex.push_back(v);
        chunk.corner.push_back(static_cast<int>(3 * t + k));
        continue;
      }
      if (stamp[v] != id) {
        stamp[v] = id;
        local[v] = static_cast<uint32_t>(chunk.vertex.size());
        chunk.vertex.push_back(v);
      }
      chunk.indices.push_back(local[v]);
    }
  }
  return chunks;
}

// The atlas as the model's image 0 (PNG in the buffer), sampler 0 and texture 0.
TextureAtlas AddAtlasTexture(tinygltf::Model* model, const ExportSurface& surface,
                             const GlbOptions& options, const std::string& what) {
  TextureAtlas atlas =
      BuildTextureAtlas(surface, options.atlas_cell_px, options.max_atlas_px, what);
  const std::vector<unsigned char> png = EncodePng(atlas, what);
  tinygltf::Image image;
  image.name = "facets_atlas";
  image.mimeType = "image/png";
  image.bufferView = AddBufferView(model, png.data(), png.size(), 0);
  model->images.push_back(image);
  tinygltf::Sampler sampler;
  // LINEAR without mipmaps: the atlas is exact only under bilinear sampling of one
  // level (mip levels would mix neighbouring cells).
  sampler.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
  sampler.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
  sampler.wrapS = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
  sampler.wrapT = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
  model->samplers.push_back(sampler);
  tinygltf::Texture texture;
  texture.sampler = 0;
  texture.source = 0;
  model->textures.push_back(texture);
  return atlas;
}

// Material 0: unlit white under the colours (texture 0 when textured), plain grey
// without colours.
void AddSurfaceMaterial(tinygltf::Model* model, bool has_color, bool textured) {
  tinygltf::Material material;
  material.name = "facets_surface";
  material.doubleSided = true;  // open surfaces: walls and roofs are seen from both sides
  if (has_color) {
    material.pbrMetallicRoughness.baseColorFactor = {1.0, 1.0, 1.0, 1.0};
    if (textured) material.pbrMetallicRoughness.baseColorTexture.index = 0;
    // Fallback for viewers without KHR_materials_unlit (the extension's recommendation).
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    material.pbrMetallicRoughness.roughnessFactor = 0.9;
    material.extensions["KHR_materials_unlit"] = tinygltf::Value(tinygltf::Value::Object{});
    model->extensionsUsed.push_back("KHR_materials_unlit");
  } else {
    material.pbrMetallicRoughness.baseColorFactor = {0.8, 0.8, 0.8, 1.0};
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    material.pbrMetallicRoughness.roughnessFactor = 0.9;
  }
  model->materials.push_back(material);
}

std::vector<float> ChunkPositions(const ExportSurface& surface, const Chunk& chunk) {
  const size_t n = chunk.vertex.size();
  std::vector<float> position(3 * n);
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      position[3 * i + c] = static_cast<float>(surface.vertices[chunk.vertex[i]][c]);
    }
  }
  return position;
}

std::vector<float> ChunkUnitNormals(const ExportSurface& surface, const Chunk& chunk) {
  const size_t n = chunk.vertex.size();
  std::vector<float> normal(3 * n);
  for (size_t i = 0; i < n; ++i) {
    // Normalise in float so the validator's unit-length test holds after rounding.
    Eigen::Vector3f v = surface.normals[chunk.vertex[i]].cast<float>();
    v /= v.norm();
    for (int c = 0; c < 3; ++c) normal[3 * i + c] = v[c];
  }
  return normal;
}

std::vector<float> ChunkUvs(const TextureAtlas& atlas, const Chunk& chunk) {
  const size_t n = chunk.vertex.size();
  std::vector<float> uv(2 * n);
  for (size_t i = 0; i < n; ++i) {
    uv[2 * i] = atlas.uv[chunk.corner[i]].x();
    uv[2 * i + 1] = atlas.uv[chunk.corner[i]].y();
  }
  return uv;
}

// Linear colours 0..1 (grey repeated for one channel).
std::vector<float> ChunkColors(const ExportSurface& surface, const Chunk& chunk) {
  const size_t n = chunk.vertex.size();
  const int ch = surface.channels;
  std::vector<float> color(3 * n);
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      color[3 * i + c] =
          surface.colors[static_cast<size_t>(chunk.vertex[i]) * ch + (ch == 3 ? c : 0)] /
          255.0f;
    }
  }
  return color;
}

// Per-vertex scalars _SIGMA and _VIEWS when asked for and present.
void AddScalarAttributes(tinygltf::Model* model, const ExportSurface& surface,
                         const Chunk& chunk, const GlbOptions& options,
                         tinygltf::Primitive* primitive) {
  const size_t n = chunk.vertex.size();
  if (options.write_sigma && !surface.sigma.empty()) {
    std::vector<float> sigma(n);
    for (size_t i = 0; i < n; ++i) sigma[i] = surface.sigma[chunk.vertex[i]];
    primitive->attributes["_SIGMA"] =
        AddAccessor(model, sigma, 1, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR,
                    TINYGLTF_TARGET_ARRAY_BUFFER);
  }
  if (options.write_views && !surface.views.empty()) {
    std::vector<float> views(n);
    for (size_t i = 0; i < n; ++i) views[i] = static_cast<float>(surface.views[chunk.vertex[i]]);
    primitive->attributes["_VIEWS"] =
        AddAccessor(model, views, 1, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR,
                    TINYGLTF_TARGET_ARRAY_BUFFER);
  }
}

// 16-bit indices when the chunk's vertices allow them, else 32-bit.
int AddIndices(tinygltf::Model* model, const Chunk& chunk) {
  if (chunk.vertex.size() <= static_cast<size_t>(kMax16BitVertices)) {
    std::vector<uint16_t> indices(chunk.indices.begin(), chunk.indices.end());
    return AddAccessor(model, indices, 1, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                       TINYGLTF_TYPE_SCALAR, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  }
  return AddAccessor(model, chunk.indices, 1, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                     TINYGLTF_TYPE_SCALAR, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
}

// One triangle primitive of material 0; its attributes appended to the buffer in the
// order POSITION, NORMAL, TEXCOORD_0, COLOR_0, _SIGMA, _VIEWS, indices.
tinygltf::Primitive ChunkPrimitive(tinygltf::Model* model, const ExportSurface& surface,
                                   const Chunk& chunk, const TextureAtlas* atlas,
                                   bool vertex_colors, const GlbOptions& options) {
  tinygltf::Primitive primitive;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  primitive.material = 0;
  primitive.attributes["POSITION"] =
      AddAccessor(model, ChunkPositions(surface, chunk), 3, TINYGLTF_COMPONENT_TYPE_FLOAT,
                  TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER, true);
  if (!surface.normals.empty()) {
    primitive.attributes["NORMAL"] =
        AddAccessor(model, ChunkUnitNormals(surface, chunk), 3, TINYGLTF_COMPONENT_TYPE_FLOAT,
                    TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER);
  }
  if (atlas != nullptr) {
    primitive.attributes["TEXCOORD_0"] =
        AddAccessor(model, ChunkUvs(*atlas, chunk), 2, TINYGLTF_COMPONENT_TYPE_FLOAT,
                    TINYGLTF_TYPE_VEC2, TINYGLTF_TARGET_ARRAY_BUFFER);
  }
  if (vertex_colors) {
    primitive.attributes["COLOR_0"] =
        AddAccessor(model, ChunkColors(surface, chunk), 3, TINYGLTF_COMPONENT_TYPE_FLOAT,
                    TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER);
  }
  AddScalarAttributes(model, surface, chunk, options, &primitive);
  primitive.indices = AddIndices(model, chunk);
  return primitive;
}

// Node "facets_origin" holds mesh 0 translated to the origin; with y_up a root node
// turns Z up into glTF's Y up. Scene 0 is the default.
void AddNodesAndScene(tinygltf::Model* model, const ExportSurface& surface, bool y_up) {
  tinygltf::Node origin_node;
  origin_node.name = "facets_origin";
  origin_node.mesh = 0;
  origin_node.translation = {surface.origin.x(), surface.origin.y(), surface.origin.z()};
  tinygltf::Scene scene;
  scene.name = "facets";
  scene.extras = GeoreferenceExtras(surface);
  if (y_up) {
    tinygltf::Node root;
    root.name = "facets_z_up_to_y_up";
    root.rotation = {-std::sqrt(0.5), 0.0, 0.0, std::sqrt(0.5)};
    root.children = {1};
    model->nodes.push_back(root);
    model->nodes.push_back(origin_node);
  } else {
    model->nodes.push_back(origin_node);
  }
  scene.nodes = {0};
  model->scenes.push_back(scene);
  model->defaultScene = 0;
}

}  // namespace

void GlbOptions::Check() const {
  if (max_primitive_vertices != 0 &&
      (max_primitive_vertices < 3 || max_primitive_vertices > kMax16BitVertices)) {
    throw std::invalid_argument("GlbOptions.max_primitive_vertices must be 0 or 3..65535, not " +
                                std::to_string(max_primitive_vertices));
  }
  if (atlas_cell_px < 5) {
    throw std::invalid_argument("GlbOptions.atlas_cell_px must be >= 5, not " +
                                std::to_string(atlas_cell_px));
  }
  if (max_atlas_px < atlas_cell_px) {
    throw std::invalid_argument("GlbOptions.max_atlas_px must be >= atlas_cell_px, not " +
                                std::to_string(max_atlas_px));
  }
}

std::string GlbBytes(const ExportSurface& surface, const GlbOptions& options,
                     const std::string& what) {
  options.Check();
  surface.Check(what);
  if (surface.triangles.empty())
    throw std::invalid_argument(what + ": the surface has no triangles");

  const bool has_color = !surface.colors.empty();
  const bool textured = has_color && options.color_mode == GlbColorMode::kTexture;
  const bool vertex_colors = has_color && options.color_mode == GlbColorMode::kVertexColors;

  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = options.generator;
  model.asset.extras = GeoreferenceExtras(surface);
  model.buffers.resize(1);

  TextureAtlas atlas;
  if (textured) atlas = AddAtlasTexture(&model, surface, options, what);
  AddSurfaceMaterial(&model, has_color, textured);

  const std::vector<Chunk> chunks =
      SplitIntoChunks(surface, textured, options.max_primitive_vertices);
  tinygltf::Mesh mesh;
  mesh.name = "facets_surface";
  for (const Chunk& chunk : chunks) {
    mesh.primitives.push_back(ChunkPrimitive(&model, surface, chunk, textured ? &atlas : nullptr,
                                             vertex_colors, options));
  }
  model.meshes.push_back(mesh);
  // The BIN chunk must be a multiple of 4 bytes; the buffer's byteLength is its length.
  while (model.buffers[0].data.size() % 4 != 0) model.buffers[0].data.push_back(0);
  AddNodesAndScene(&model, surface, options.y_up);

  std::ostringstream out;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, out, false, true)) {
    throw std::runtime_error(what + ": tinygltf could not serialise the model");
  }
  return std::move(out).str();
}

void WriteGlb(const std::string& path, const ExportSurface& surface, const GlbOptions& options) {
  WriteFileAtomically(path, GlbBytes(surface, options, path));
}

}  // namespace facets
