#include "engine/solver/adjustment_options.h"

#include <stdexcept>

namespace facets {

Regularisation RegularisationFromName(const std::string& name) {
  if (name == "curvature") return Regularisation::kCurvature;
  if (name == "adaptive") return Regularisation::kAdaptive;
  if (name == "none") return Regularisation::kNone;
  throw std::invalid_argument("unknown regularisation '" + name +
                              "' (known: curvature, adaptive, none)");
}

RadiometricModel RadiometricModelFromName(const std::string& name) {
  if (name == "none") return RadiometricModel::kNone;
  if (name == "constant") return RadiometricModel::kConstant;
  if (name == "linear") return RadiometricModel::kLinear;
  throw std::invalid_argument("unknown radiometric model '" + name +
                              "' (known: none, constant, linear)");
}

Displacement DisplacementFromName(const std::string& name) {
  if (name == "normal") return Displacement::kNormal;
  if (name == "vertical") return Displacement::kVertical;
  throw std::invalid_argument("unknown displacement '" + name + "' (known: normal, vertical)");
}

WindowSolver WindowSolverFromName(const std::string& name) {
  if (name == "ldlt") return WindowSolver::kLdlt;
  if (name == "pcg") return WindowSolver::kPcg;
  throw std::invalid_argument("unknown window solver '" + name + "' (known: ldlt, pcg)");
}

std::string WindowSolverName(WindowSolver s) {
  switch (s) {
    case WindowSolver::kLdlt: return "ldlt";
    case WindowSolver::kPcg: return "pcg";
  }
  return "?";
}

std::string RegularisationName(Regularisation r) {
  switch (r) {
    case Regularisation::kCurvature: return "curvature";
    case Regularisation::kAdaptive: return "adaptive";
    case Regularisation::kNone: return "none";
  }
  return "?";
}

std::string RadiometricModelName(RadiometricModel m) {
  switch (m) {
    case RadiometricModel::kNone: return "none";
    case RadiometricModel::kConstant: return "constant";
    case RadiometricModel::kLinear: return "linear";
  }
  return "?";
}

void AdjustmentOptions::Check() const {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("adjustment options: " + what);
  };
  if (!(lambda >= 0.0)) fail("lambda must be >= 0");
  if (reference_image < 0) fail("reference_image must be >= 0");
  if (!(break_off > 0.0)) fail("break_off must be > 0");
  if (max_iterations < 1) fail("max_iterations must be >= 1");
  if (stall_iterations < 0) fail("stall_iterations must be >= 0");
  if (!(stall_ratio >= 0.0)) fail("stall_ratio must be >= 0");
  if (!(max_step >= 0.0)) fail("max_step must be >= 0");
  if (!(min_cos_incidence >= 0.0 && min_cos_incidence < 1.0))
    fail("min_cos_incidence must lie in [0, 1)");
  if (!(crease_angle_deg > 0.0 && crease_angle_deg <= 180.0))
    fail("crease_angle_deg must lie in (0, 180]");
  if (!(grey_ridge >= 0.0)) fail("grey_ridge must be >= 0");
  if (min_views < 0) fail("min_views must be >= 0");
  if (!(min_view_share >= 0.0 && min_view_share <= 1.0)) fail("min_view_share must lie in [0, 1]");
  if (!(max_sigma >= 0.0)) fail("max_sigma must be >= 0");
  if (!(robust_k >= 0.0)) fail("robust_k must be >= 0");
  if (!(reject_k >= 0.0)) fail("reject_k must be >= 0");
  if (robust_k > 0.0 && reject_k > 0.0 && reject_k < robust_k) fail("reject_k must be >= robust_k");
  if (!(silhouette_weight >= 0.0)) fail("silhouette_weight must be >= 0");
  if (!(silhouette_rim_cos >= 0.0 && silhouette_rim_cos <= 1.0)) fail("silhouette_rim_cos must lie in [0, 1]");
  if (!(silhouette_outside_px >= 0.0)) fail("silhouette_outside_px must be >= 0");
  if (!(silhouette_inside_px >= 0.0)) fail("silhouette_inside_px must be >= 0");
  std::string error;
  if (!pcg.Check(&error)) fail(error);
}

}  // namespace facets
