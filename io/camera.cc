#include "io/camera.h"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

namespace facets {
namespace {

struct ModelInfo {
  CameraModel model;
  const char* name;
  int num_params;
};

constexpr ModelInfo kModels[] = {
    {CameraModel::kSimplePinhole, "SIMPLE_PINHOLE", 3},
    {CameraModel::kPinhole, "PINHOLE", 4},
    {CameraModel::kSimpleRadial, "SIMPLE_RADIAL", 4},
    {CameraModel::kRadial, "RADIAL", 5},
    {CameraModel::kOpenCV, "OPENCV", 8},
};

const ModelInfo& Info(CameraModel model) {
  for (const auto& info : kModels) {
    if (info.model == model) return info;
  }
  throw std::logic_error("unknown camera model enum");
}

bool HasSeparateFocals(CameraModel model) {
  return model == CameraModel::kPinhole || model == CameraModel::kOpenCV;
}

// Distortion coefficients in the order k1, k2, p1, p2 (absent ones zero).
struct Coefficients {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0;
};

Coefficients DistortionOf(const Camera& camera) {
  Coefficients c;
  const auto& p = camera.params;
  switch (camera.model) {
    case CameraModel::kSimpleRadial:
      c.k1 = p[3];
      break;
    case CameraModel::kRadial:
      c.k1 = p[3];
      c.k2 = p[4];
      break;
    case CameraModel::kOpenCV:
      c.k1 = p[4];
      c.k2 = p[5];
      c.p1 = p[6];
      c.p2 = p[7];
      break;
    default:
      break;
  }
  return c;
}

// Distorted normalised coordinates and their Jacobian d(distorted)/d(undistorted).
Eigen::Vector2d DistortWithJacobian(const Coefficients& c, const Eigen::Vector2d& uv,
                                    Eigen::Matrix2d* jacobian) {
  const double u = uv.x(), v = uv.y();
  const double u2 = u * u, v2 = v * v, uv_ = u * v, r2 = u2 + v2;
  const double radial = c.k1 * r2 + c.k2 * r2 * r2;
  const Eigen::Vector2d out(u + u * radial + 2 * c.p1 * uv_ + c.p2 * (r2 + 2 * u2),
                            v + v * radial + 2 * c.p2 * uv_ + c.p1 * (r2 + 2 * v2));
  if (jacobian) {
    const double dradial_dr2 = c.k1 + 2 * c.k2 * r2;
    // d radial / du = dradial_dr2 * 2u.
    const double dru = dradial_dr2 * 2 * u, drv = dradial_dr2 * 2 * v;
    (*jacobian)(0, 0) = 1 + radial + u * dru + 2 * c.p1 * v + c.p2 * 6 * u;
    (*jacobian)(0, 1) = u * drv + 2 * c.p1 * u + c.p2 * 2 * v;
    (*jacobian)(1, 0) = v * dru + 2 * c.p2 * v + c.p1 * 2 * u;
    (*jacobian)(1, 1) = 1 + radial + v * drv + 2 * c.p2 * u + c.p1 * 6 * v;
  }
  return out;
}

}  // namespace

CameraModel CameraModelFromName(const std::string& name) {
  for (const auto& info : kModels) {
    if (name == info.name) return info.model;
  }
  throw std::invalid_argument(
      "camera model '" + name +
      "' is not supported (known: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, "
      "OPENCV)");
}

std::string CameraModelName(CameraModel model) { return Info(model).name; }

int CameraModelNumParams(CameraModel model) { return Info(model).num_params; }

Camera Camera::Create(CameraModel model, double fx, double fy, double cx, double cy,
                      int width, int height) {
  Camera camera;
  camera.model = model;
  camera.width = width;
  camera.height = height;
  camera.params.assign(CameraModelNumParams(model), 0.0);
  if (HasSeparateFocals(model)) {
    camera.params[0] = fx;
    camera.params[1] = fy;
    camera.params[2] = cx;
    camera.params[3] = cy;
  } else {
    camera.params[0] = fx;
    camera.params[1] = cx;
    camera.params[2] = cy;
    (void)fy;
  }
  return camera;
}

double Camera::FocalX() const { return params[0]; }
double Camera::FocalY() const { return HasSeparateFocals(model) ? params[1] : params[0]; }
double Camera::PrincipalX() const { return HasSeparateFocals(model) ? params[2] : params[1]; }
double Camera::PrincipalY() const { return HasSeparateFocals(model) ? params[3] : params[2]; }

bool Camera::HasDistortion() const {
  const Coefficients c = DistortionOf(*this);
  return c.k1 != 0 || c.k2 != 0 || c.p1 != 0 || c.p2 != 0;
}

void Camera::Check() const {
  const std::string who = "camera " + std::to_string(camera_id) + " (" +
                          CameraModelName(model) + ")";
  if (static_cast<int>(params.size()) != CameraModelNumParams(model)) {
    throw std::invalid_argument(who + ": expected " +
                                std::to_string(CameraModelNumParams(model)) +
                                " parameters, got " + std::to_string(params.size()));
  }
  for (double p : params) {
    if (!std::isfinite(p)) throw std::invalid_argument(who + ": parameter is not finite");
  }
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument(who + ": image size must be positive");
  }
  if (!(FocalX() > 0) || !(FocalY() > 0)) {
    throw std::invalid_argument(who + ": focal length must be positive");
  }
}

Eigen::Vector2d Camera::Distort(const Eigen::Vector2d& undistorted) const {
  return DistortWithJacobian(DistortionOf(*this), undistorted, nullptr);
}

Eigen::Vector2d Camera::Undistort(const Eigen::Vector2d& distorted) const {
  const Coefficients c = DistortionOf(*this);
  if (c.k1 == 0 && c.k2 == 0 && c.p1 == 0 && c.p2 == 0) return distorted;
  // Newton on distort(uv) = distorted, starting at the distorted point. Converges in a
  // handful of steps for the distortions real lenses have.
  Eigen::Vector2d uv = distorted;
  for (int iteration = 0; iteration < 100; ++iteration) {
    Eigen::Matrix2d jacobian;
    const Eigen::Vector2d residual = DistortWithJacobian(c, uv, &jacobian) - distorted;
    const Eigen::Vector2d step = jacobian.partialPivLu().solve(residual);
    uv -= step;
    if (step.squaredNorm() < 1e-28) break;
  }
  return uv;
}

Eigen::Vector2d Camera::ImageFromCam(const Eigen::Vector3d& point_in_cam) const {
  const Eigen::Vector2d uv = Distort(point_in_cam.head<2>() / point_in_cam.z());
  return {FocalX() * uv.x() + PrincipalX(), FocalY() * uv.y() + PrincipalY()};
}

Eigen::Vector3d Camera::CamFromImage(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d distorted((pixel.x() - PrincipalX()) / FocalX(),
                                  (pixel.y() - PrincipalY()) / FocalY());
  const Eigen::Vector2d uv = Undistort(distorted);
  return {uv.x(), uv.y(), 1.0};
}

Camera Camera::Scaled(double factor) const {
  Camera scaled = *this;
  scaled.width = static_cast<int>(std::ceil(width * factor - 1e-9));
  scaled.height = static_cast<int>(std::ceil(height * factor - 1e-9));
  const int num_focal_and_pp = HasSeparateFocals(model) ? 4 : 3;
  for (int i = 0; i < num_focal_and_pp; ++i) scaled.params[i] *= factor;
  return scaled;
}

Camera Camera::WithPrincipalPointShifted(double dx, double dy) const {
  Camera shifted = *this;
  const int cx_index = HasSeparateFocals(model) ? 2 : 1;
  shifted.params[cx_index] += dx;
  shifted.params[cx_index + 1] += dy;
  return shifted;
}

}  // namespace facets
