#include "scenes/truth_mesh.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>

namespace facets {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr int kMaxCellsPerAxis = 4000;

// Local frame of a shape: u along its azimuth, v to the left, z up.
struct Frame {
  Eigen::Vector2d c;
  double ca, sa;
  explicit Frame(const Shape& s)
      : c(s.centre.head<2>()), ca(std::cos(s.azimuth_deg * kDeg)),
        sa(std::sin(s.azimuth_deg * kDeg)) {}
  Eigen::Vector3d Point(double u, double v, double z) const {
    return Eigen::Vector3d(c.x() + ca * u - sa * v, c.y() + sa * u + ca * v, z);
  }
  Eigen::Vector3d Dir(double u, double v, double z) const {
    return Eigen::Vector3d(ca * u - sa * v, sa * u + ca * v, z);
  }
};

class MeshBuilder {
 public:
  MeshBuilder(TruthMesh* mesh, int shape) : m_(mesh), shape_(shape) {}

  int Vertex(const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    m_->vertices.push_back(p);
    m_->normals.push_back(n.normalized());
    return static_cast<int>(m_->vertices.size()) - 1;
  }
  // Adds a triangle, flipped if needed so its geometric normal agrees with `outward`.
  void Triangle(int a, int b, int c, const Eigen::Vector3d& outward, int label, bool smooth) {
    const auto& V = m_->vertices;
    const Eigen::Vector3d n = (V[b] - V[a]).cross(V[c] - V[a]);
    if (n.squaredNorm() == 0) return;  // degenerate (e.g. hip ridge of zero length)
    if (n.dot(outward) < 0) std::swap(b, c);
    m_->faces.emplace_back(a, b, c);
    m_->labels.push_back(label);
    m_->smooth.push_back(smooth ? 1 : 0);
    m_->shape_index.push_back(shape_);
  }
  // Planar polygon (convex, given in order) fanned from its first corner.
  void Polygon(const std::vector<Eigen::Vector3d>& corners, const Eigen::Vector3d& outward,
               int label) {
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (size_t i = 1; i + 1 < corners.size(); ++i) {
      n += (corners[i] - corners[0]).cross(corners[i + 1] - corners[0]);
    }
    if (n.squaredNorm() == 0) return;
    n.normalize();
    if (n.dot(outward) < 0) n = -n;
    std::vector<int> ids;
    for (const auto& p : corners) ids.push_back(Vertex(p, n));
    for (size_t i = 1; i + 1 < ids.size(); ++i) Triangle(ids[0], ids[i], ids[i + 1], n, label, false);
  }
  // Grid over (s, t) in [0,1]^2 with nu x nv cells; point(s,t), normal(s,t).
  void Grid(int nu, int nv, const std::function<Eigen::Vector3d(double, double)>& point,
            const std::function<Eigen::Vector3d(double, double)>& normal, int label,
            bool smooth) {
    const int base = static_cast<int>(m_->vertices.size());
    for (int j = 0; j <= nv; ++j) {
      for (int i = 0; i <= nu; ++i) {
        const double s = static_cast<double>(i) / nu, t = static_cast<double>(j) / nv;
        Vertex(point(s, t), normal(s, t));
      }
    }
    auto id = [&](int i, int j) { return base + j * (nu + 1) + i; };
    for (int j = 0; j < nv; ++j) {
      for (int i = 0; i < nu; ++i) {
        const double s = (i + 0.5) / nu, t = (j + 0.5) / nv;
        const Eigen::Vector3d n = normal(s, t);
        Triangle(id(i, j), id(i + 1, j), id(i + 1, j + 1), n, label, smooth);
        Triangle(id(i, j), id(i + 1, j + 1), id(i, j + 1), n, label, smooth);
      }
    }
  }

 private:
  TruthMesh* m_;
  int shape_;
};

int Cells(double extent, double step) {
  const int n = static_cast<int>(std::ceil(extent / step - 1e-9));
  return std::clamp(n, 1, kMaxCellsPerAxis);
}

// Edge length for a curvature kappa so that the sagitta kappa * h^2 / 8 <= tolerance.
double StepFor(double kappa, double tolerance, double fallback) {
  if (kappa <= 0) return fallback;
  return std::min(fallback, std::sqrt(8 * tolerance / kappa));
}

double TerrainZ(const Shape& s, double x, double y) {
  double z = s.centre.z();
  for (const Eigen::Vector4d& w : s.waves) {
    const double d = std::cos(w[2] * kDeg) * x + std::sin(w[2] * kDeg) * y;
    z += w[0] * std::sin(2 * M_PI * d / w[1] + w[3] * kDeg);
  }
  return z;
}

Eigen::Vector2d TerrainGradient(const Shape& s, double x, double y) {
  Eigen::Vector2d g = Eigen::Vector2d::Zero();
  for (const Eigen::Vector4d& w : s.waves) {
    const Eigen::Vector2d dir(std::cos(w[2] * kDeg), std::sin(w[2] * kDeg));
    const double k = 2 * M_PI / w[1];
    g += w[0] * k * std::cos(k * dir.dot(Eigen::Vector2d(x, y)) + w[3] * kDeg) * dir;
  }
  return g;
}

void AddTerrain(const Scene& scene, const Shape& s, MeshBuilder* b) {
  double kappa = 0;
  for (const auto& w : s.waves) kappa += std::abs(w[0]) * std::pow(2 * M_PI / w[1], 2);
  const double step =
      s.step > 0 ? s.step : StepFor(kappa, scene.sagitta_tolerance, std::max(s.length, s.width) / 4);
  const Frame f(s);
  const int nu = Cells(s.length, step), nv = Cells(s.width, step);
  auto xy = [&](double a, double t) {
    return f.Point((a - 0.5) * s.length, (t - 0.5) * s.width, 0);
  };
  b->Grid(
      nu, nv,
      [&](double a, double t) {
        Eigen::Vector3d p = xy(a, t);
        p.z() = TerrainZ(s, p.x(), p.y());
        return p;
      },
      [&](double a, double t) {
        const Eigen::Vector3d p = xy(a, t);
        const Eigen::Vector2d g = TerrainGradient(s, p.x(), p.y());
        return Eigen::Vector3d(-g.x(), -g.y(), 1).normalized();
      },
      s.label, !s.waves.empty());
}

void AddPlane(const Shape& s, MeshBuilder* b) {
  const Frame f(s);
  const double step = s.step > 0 ? s.step : 10.0;
  b->Grid(
      Cells(s.length, step), Cells(s.width, step),
      [&](double a, double t) {
        return f.Point((a - 0.5) * s.length, (t - 0.5) * s.width, s.centre.z());
      },
      [](double, double) { return Eigen::Vector3d::UnitZ(); }, s.label, false);
}

// z = centre.z + (width/2 - |v|) tan(slope): ridge along u at v = 0.
void AddGableRoof(const Shape& s, MeshBuilder* b) {
  const Frame f(s);
  const double t = std::tan(s.slope_deg * kDeg);
  const double step = s.step > 0 ? s.step : 2.0;
  for (int side : {-1, 1}) {
    // Plane normal: rises towards the ridge, so it tilts towards the eave side.
    const Eigen::Vector3d n = f.Dir(0, side * t, 1).normalized();
    b->Grid(
        Cells(s.length, step), Cells(0.5 * s.width, step),
        [&](double a, double q) {
          const double v = side * q * 0.5 * s.width;  // q = 0 ridge, 1 eave
          return f.Point((a - 0.5) * s.length, v, s.centre.z() + (0.5 * s.width - std::abs(v)) * t);
        },
        [&](double, double) { return n; }, s.label, false);
  }
}

// z = centre.z + height * (1 - (2 v / width)^2).
void AddParabolicCylinder(const Scene& scene, const Shape& s, MeshBuilder* b) {
  const Frame f(s);
  const double kappa = 8 * std::abs(s.height) / (s.width * s.width);
  const double step_v = s.step > 0 ? s.step : StepFor(kappa, scene.sagitta_tolerance, 2.0);
  const double step_u = s.step > 0 ? s.step : 1.0;  // straight along the axis
  auto v_of = [&](double q) { return (q - 0.5) * s.width; };
  b->Grid(
      Cells(s.length, step_u), Cells(s.width, step_v),
      [&](double a, double q) {
        const double v = v_of(q);
        const double r = 2 * v / s.width;
        return f.Point((a - 0.5) * s.length, v, s.centre.z() + s.height * (1 - r * r));
      },
      [&](double, double q) {
        const double dzdv = -8 * s.height * v_of(q) / (s.width * s.width);
        return f.Dir(0, -dzdv, 1).normalized();
      },
      s.label, true);
}

void AddBuilding(const Scene& scene, const Shape& s, MeshBuilder* b) {
  const Frame f(s);
  const double L = s.length, W = s.width;
  const double ground = GroundHeightAt(scene, s.centre.x(), s.centre.y()).value_or(s.centre.z());
  // Walls start below the lowest terrain point of the footprint: no gap at the foot.
  double lowest = ground;
  for (int i = -1; i <= 1; i += 2) {
    for (int j = -1; j <= 1; j += 2) {
      const Eigen::Vector3d c = f.Point(0.5 * i * L, 0.5 * j * W, 0);
      lowest = std::min(lowest, GroundHeightAt(scene, c.x(), c.y()).value_or(ground));
    }
  }
  const double z_bottom = lowest - 1.0;
  const double z_eave = ground + s.height;
  // Outward offset of wall i at height z (lean measured from the ground).
  auto offset = [&](int i, double z) { return (z - ground) * std::tan(s.wall_lean_deg[i] * kDeg); };
  // Corner between wall i and wall i+1 (walls: 0 +u, 1 +v, 2 -u, 3 -v).
  const Eigen::Vector2d normals[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  const double half[4] = {0.5 * L, 0.5 * W, 0.5 * L, 0.5 * W};
  auto corner = [&](int i, double z) {
    const int j = (i + 1) % 4;
    const Eigen::Vector2d uv =
        normals[i] * (half[i] + offset(i, z)) + normals[j] * (half[j] + offset(j, z));
    return f.Point(uv.x(), uv.y(), z);
  };
  for (int i = 0; i < 4; ++i) {
    const int prev = (i + 3) % 4;
    const Eigen::Vector3d out = f.Dir(normals[i].x(), normals[i].y(), 0);
    b->Polygon({corner(prev, z_bottom), corner(i, z_bottom), corner(i, z_eave), corner(prev, z_eave)},
               out, kLabelWall);
  }
  // Eave rectangle (still a rectangle: each side moved along its own normal).
  const double u0 = -0.5 * L - offset(2, z_eave), u1 = 0.5 * L + offset(0, z_eave);
  const double v0 = -0.5 * W - offset(3, z_eave), v1 = 0.5 * W + offset(1, z_eave);
  const double uc = 0.5 * (u0 + u1), vc = 0.5 * (v0 + v1);
  const double Le = u1 - u0, We = v1 - v0;
  auto P = [&](double u, double v, double z) { return f.Point(u, v, z); };
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  const double t = std::tan(s.slope_deg * kDeg);
  switch (s.roof) {
    case RoofType::kFlat:
      b->Polygon({P(u0, v0, z_eave), P(u1, v0, z_eave), P(u1, v1, z_eave), P(u0, v1, z_eave)}, up,
                 s.label);
      break;
    case RoofType::kGable: {
      const double zr = z_eave + 0.5 * We * t;
      b->Polygon({P(u0, v0, z_eave), P(u1, v0, z_eave), P(u1, vc, zr), P(u0, vc, zr)},
                 f.Dir(0, -t, 1), s.label);
      b->Polygon({P(u0, v1, z_eave), P(u1, v1, z_eave), P(u1, vc, zr), P(u0, vc, zr)},
                 f.Dir(0, t, 1), s.label);
      b->Polygon({P(u0, v0, z_eave), P(u0, v1, z_eave), P(u0, vc, zr)}, f.Dir(-1, 0, 0),
                 kLabelWall);
      b->Polygon({P(u1, v0, z_eave), P(u1, v1, z_eave), P(u1, vc, zr)}, f.Dir(1, 0, 0),
                 kLabelWall);
      break;
    }
    case RoofType::kHip: {
      const double h = 0.5 * We * t;
      const double zr = z_eave + h;
      const double r0 = uc - std::max(0.0, 0.5 * Le - 0.5 * We);
      const double r1 = uc + std::max(0.0, 0.5 * Le - 0.5 * We);
      b->Polygon({P(u0, v0, z_eave), P(u1, v0, z_eave), P(r1, vc, zr), P(r0, vc, zr)},
                 f.Dir(0, -t, 1), s.label);
      b->Polygon({P(u0, v1, z_eave), P(u1, v1, z_eave), P(r1, vc, zr), P(r0, vc, zr)},
                 f.Dir(0, t, 1), s.label);
      b->Polygon({P(u0, v0, z_eave), P(u0, v1, z_eave), P(r0, vc, zr)}, f.Dir(-t, 0, 1),
                 s.label);
      b->Polygon({P(u1, v0, z_eave), P(u1, v1, z_eave), P(r1, vc, zr)}, f.Dir(t, 0, 1),
                 s.label);
      break;
    }
  }
}

struct Lobe {
  Eigen::Vector3d dir;
  double freq, phase, weight;
};

std::vector<Lobe> BlobLobes(const Shape& s) {
  std::mt19937 rng(static_cast<unsigned>(s.lobes_seed) * 7919u + 3u);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Lobe> lobes(6);
  double sum = 0;
  for (Lobe& l : lobes) {
    const double z = 2 * unit(rng) - 1, phi = 2 * M_PI * unit(rng);
    const double r = std::sqrt(1 - z * z);
    l.dir = Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
    l.freq = 2 + 3 * unit(rng);
    l.phase = 2 * M_PI * unit(rng);
    l.weight = 0.5 + unit(rng);
    sum += l.weight;
  }
  for (Lobe& l : lobes) l.weight /= sum;
  return lobes;
}

void AddBlob(const Scene& scene, const Shape& s, MeshBuilder* b, TruthMesh* mesh) {
  const std::vector<Lobe> lobes = BlobLobes(s);
  auto radius = [&](const Eigen::Vector3d& u) {
    double r = 0;
    for (const Lobe& l : lobes) r += l.weight * std::sin(l.freq * u.dot(l.dir) + l.phase);
    return s.radius * (1 + s.lobe_amplitude * r);
  };
  // Curvature bound of r(u) on the unit sphere: 1/R plus the lobes' second derivative.
  const double kappa = (1 + s.lobe_amplitude * 25) / (s.radius * (1 - s.lobe_amplitude));
  const double step = s.step > 0 ? s.step : StepFor(kappa, scene.sagitta_tolerance, s.radius / 4);
  const double rmax = s.radius * (1 + s.lobe_amplitude);
  const int n_theta = std::clamp(static_cast<int>(std::ceil(M_PI * rmax / step)), 8, 2000);
  const int n_phi = 2 * n_theta;
  const size_t first_vertex = mesh->vertices.size();
  const size_t first_face = mesh->faces.size();
  auto point = [&](int it, int ip) {
    const double theta = M_PI * it / n_theta, phi = 2 * M_PI * ip / n_phi;
    const Eigen::Vector3d u(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                            std::cos(theta));
    return Eigen::Vector3d(s.centre + radius(u) * u);
  };
  // Rings it = 1 .. n_theta-1 with n_phi vertices each, plus two poles.
  const int north = b->Vertex(point(0, 0), Eigen::Vector3d::UnitZ());
  std::vector<int> ring_start;
  for (int it = 1; it < n_theta; ++it) {
    ring_start.push_back(static_cast<int>(mesh->vertices.size()));
    for (int ip = 0; ip < n_phi; ++ip) b->Vertex(point(it, ip), Eigen::Vector3d::UnitZ());
  }
  const int south = b->Vertex(point(n_theta, 0), -Eigen::Vector3d::UnitZ());
  auto id = [&](int ring, int ip) { return ring_start[ring] + (ip % n_phi); };
  auto outward = [&](int a, int bb, int c) {
    return Eigen::Vector3d((mesh->vertices[a] + mesh->vertices[bb] + mesh->vertices[c]) / 3 -
                           s.centre);
  };
  const int rings = n_theta - 1;
  for (int ip = 0; ip < n_phi; ++ip) {
    b->Triangle(north, id(0, ip), id(0, ip + 1), outward(north, id(0, ip), id(0, ip + 1)),
                s.label, true);
    b->Triangle(south, id(rings - 1, ip), id(rings - 1, ip + 1),
                outward(south, id(rings - 1, ip), id(rings - 1, ip + 1)), s.label, true);
  }
  for (int r = 0; r + 1 < rings; ++r) {
    for (int ip = 0; ip < n_phi; ++ip) {
      const int a = id(r, ip), c = id(r, ip + 1), d = id(r + 1, ip), e = id(r + 1, ip + 1);
      b->Triangle(a, d, e, outward(a, d, e), s.label, true);
      b->Triangle(a, e, c, outward(a, e, c), s.label, true);
    }
  }
  // Vertex normals: area-weighted mean of the adjacent face normals (the mesh is fine
  // enough that this is within a fraction of a degree of the exact normal).
  for (size_t v = first_vertex; v < mesh->vertices.size(); ++v) {
    mesh->normals[v].setZero();
  }
  for (size_t fi = first_face; fi < mesh->faces.size(); ++fi) {
    const Eigen::Vector3i& F = mesh->faces[fi];
    const Eigen::Vector3d n = (mesh->vertices[F[1]] - mesh->vertices[F[0]])
                                  .cross(mesh->vertices[F[2]] - mesh->vertices[F[0]]);
    for (int k = 0; k < 3; ++k) mesh->normals[F[k]] += n;
  }
  for (size_t v = first_vertex; v < mesh->vertices.size(); ++v) mesh->normals[v].normalize();
}

void AddMeshFile(const Shape& s, TruthMesh* mesh, int shape_index) {
  const MeshData data = ReadMesh(s.mesh_path);
  const Frame f(s);
  const int base = static_cast<int>(mesh->vertices.size());
  for (const Eigen::Vector3d& p : data.vertices) {
    Eigen::Vector3d q = f.Point(p.x(), p.y(), p.z() + s.centre.z());
    mesh->vertices.push_back(q);
    mesh->normals.push_back(Eigen::Vector3d::UnitZ());
  }
  for (size_t i = 0; i < data.faces.size(); ++i) {
    mesh->faces.push_back(data.faces[i] + Eigen::Vector3i::Constant(base));
    mesh->labels.push_back(data.face_labels.empty() ? s.label : data.face_labels[i]);
    mesh->smooth.push_back(0);  // no trusted normals: shade with the face normal
    mesh->shape_index.push_back(shape_index);
  }
}

}  // namespace

Eigen::Vector3d TruthMesh::FaceNormal(int face) const {
  const Eigen::Vector3i& F = faces[face];
  return (vertices[F[1]] - vertices[F[0]]).cross(vertices[F[2]] - vertices[F[0]]).normalized();
}

Eigen::Vector3d TruthMesh::ShadingNormal(int face, double u, double v) const {
  if (!smooth[face]) return FaceNormal(face);
  const Eigen::Vector3i& F = faces[face];
  return ((1 - u - v) * normals[F[0]] + u * normals[F[1]] + v * normals[F[2]]).normalized();
}

Eigen::Vector3d TruthMesh::Point(int face, double u, double v) const {
  const Eigen::Vector3i& F = faces[face];
  return (1 - u - v) * vertices[F[0]] + u * vertices[F[1]] + v * vertices[F[2]];
}

MeshData TruthMesh::ToMeshData() const {
  MeshData data;
  data.vertices = vertices;
  data.faces = faces;
  data.normals = normals;
  data.face_labels = labels;
  return data;
}

std::optional<double> GroundHeightAt(const Scene& scene, double x, double y) {
  for (const Shape& s : scene.surface) {
    if (s.type != ShapeType::kTerrain && s.type != ShapeType::kPlane) continue;
    const Frame f(s);
    const Eigen::Vector2d d = Eigen::Vector2d(x, y) - f.c;
    const double u = f.ca * d.x() + f.sa * d.y(), v = -f.sa * d.x() + f.ca * d.y();
    if (std::abs(u) > 0.5 * s.length || std::abs(v) > 0.5 * s.width) continue;
    return s.type == ShapeType::kTerrain ? TerrainZ(s, x, y) : s.centre.z();
  }
  return std::nullopt;
}

TruthMesh BuildTruthMesh(const Scene& scene) {
  TruthMesh mesh;
  for (size_t i = 0; i < scene.surface.size(); ++i) {
    const Shape& s = scene.surface[i];
    MeshBuilder b(&mesh, static_cast<int>(i));
    switch (s.type) {
      case ShapeType::kTerrain: AddTerrain(scene, s, &b); break;
      case ShapeType::kPlane: AddPlane(s, &b); break;
      case ShapeType::kGableRoof: AddGableRoof(s, &b); break;
      case ShapeType::kParabolicCylinder: AddParabolicCylinder(scene, s, &b); break;
      case ShapeType::kBuilding: AddBuilding(scene, s, &b); break;
      case ShapeType::kBlob: AddBlob(scene, s, &b, &mesh); break;
      case ShapeType::kMesh: AddMeshFile(s, &mesh, static_cast<int>(i)); break;
    }
  }
  return mesh;
}

}  // namespace facets
