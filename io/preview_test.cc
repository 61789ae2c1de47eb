#include "io/preview.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <utility>

#include "io/image_io.h"
#include "io/products_dir_for_testing.h"

namespace facets {
namespace {

// A gable roof 24 m x 24 m (ridge along X at y = 0, planes sloping 20 degrees down to
// the north and the south) with a grey-value ramp along X from 40 to 220.
ExportSurface GableRoof() {
  ExportSurface s;
  const int n = 25;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = i - 12.0, y = j - 12.0;
      s.vertices.emplace_back(x, y, 8.0 - std::abs(y) * std::tan(20.0 * M_PI / 180.0));
      s.colors.push_back(static_cast<float>(40.0 + 180.0 * i / (n - 1)));
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i;
      s.triangles.emplace_back(a, a + 1, a + n + 1);
      s.triangles.emplace_back(a, a + n + 1, a + n);
    }
  }
  s.origin = Eigen::Vector3d(500000.0, 5400000.0, 300.0);
  return s;
}

struct PanelStats {
  double background_share = 0.0;
  bool border_is_background = true;  // the outermost rows and columns
  double mean_surface_grey = 0.0;
};

PanelStats Panel(const ImagePlanes& image, int x0, int width, const PreviewOptions& o) {
  PanelStats stats;
  long long background = 0, surface = 0;
  double sum = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = x0; x < x0 + width; ++x) {
      bool is_background = true;
      for (int c = 0; c < 3; ++c) is_background = is_background && image.at(c, x, y) == o.background[c];
      const bool border = y == 0 || y == image.height - 1 || x == x0 || x == x0 + width - 1;
      if (border && !is_background) stats.border_is_background = false;
      if (is_background) {
        ++background;
      } else {
        ++surface;
        sum += image.at(0, x, y);
      }
    }
  }
  stats.background_share = static_cast<double>(background) / (static_cast<double>(width) * image.height);
  stats.mean_surface_grey = surface > 0 ? sum / surface : 0.0;
  return stats;
}

// The picture as planes (channel-major), as Panel reads it.
ImagePlanes Planes(const PreviewImage& picture) {
  ImagePlanes planes;
  planes.width = picture.width;
  planes.height = picture.height;
  planes.channels = 3;
  const size_t n = static_cast<size_t>(picture.width) * picture.height;
  planes.data.resize(3 * n);
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) planes.data[c * n + i] = picture.rgb[3 * i + c];
  }
  return planes;
}

TEST(Preview, TwoPanelsOfTheWholeSurfaceWrittenAsPng) {
  const ExportSurface surface = GableRoof();
  const PreviewOptions options;
  const std::string path = (ProductsDir() / "preview_gable.png").string();
  WritePreview(path, surface, options);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  const ImagePlanes image = ReadImage(path);
  ASSERT_EQ(image.width, 1200);
  ASSERT_EQ(image.height, 500);
  ASSERT_EQ(image.channels, 3);
  const PanelStats shaded = Panel(image, 0, 600, options);
  const PanelStats textured = Panel(image, 600, 600, options);
  std::cout << "preview " << image.width << " x " << image.height << ": background "
            << shaded.background_share << " (shaded) / " << textured.background_share
            << " (textured); mean surface grey " << shaded.mean_surface_grey << " / "
            << textured.mean_surface_grey << "\n";
  // The surface fills a good part of each panel and lies wholly inside it. A square
  // seen along its diagonal covers half of its bounding box, which fills the panel's
  // width but not its height: about 2/3 of the panel stays background (measured 0.68).
  EXPECT_LT(shaded.background_share, 0.75);
  EXPECT_LT(textured.background_share, 0.75);
  EXPECT_TRUE(shaded.border_is_background);
  EXPECT_TRUE(textured.border_is_background);
  // Same visibility in both panels: the same pixels are background.
  EXPECT_NEAR(shaded.background_share, textured.background_share, 1e-9);
  // Textured: the colour ramp's mean (130) up to the oblique view's foreshortening.
  EXPECT_NEAR(textured.mean_surface_grey, 130.0, 15.0);

  // Shaded: light from the north-west; the north-facing roof plane (y > 0) is lit more
  // steeply than the south-facing one. Compare the mean grey of the two planes by
  // rendering each plane alone.
  auto plane_grey = [&](bool north) {
    ExportSurface half = surface;
    half.triangles.clear();
    for (const Eigen::Vector3i& t : surface.triangles) {
      const double y = (surface.vertices[t[0]] + surface.vertices[t[1]] + surface.vertices[t[2]]).y() / 3.0;
      if ((y > 0.0) == north) half.triangles.push_back(t);
    }
    return Panel(Planes(RenderPreview(half, options)), 0, options.panel_width, options).mean_surface_grey;
  };
  const double north = plane_grey(true), south = plane_grey(false);
  std::cout << "shaded roof planes: north-facing " << north << ", south-facing " << south << "\n";
  EXPECT_GT(north, south + 10.0);
}


// A facade as the fountain's model has it: a wall 8 m x 6 m in the x-z plane facing
// +Y (towards the cameras), Z pointing DOWN, with horizontal grooves (relief) every
// metre; grey 220 on the upper half (z < 0), 40 on the lower half.
ExportSurface Facade() {
  ExportSurface s;
  const int nx = 33, nz = 25;
  for (int k = 0; k < nz; ++k) {
    for (int i = 0; i < nx; ++i) {
      const double x = 0.25 * i - 4.0, z = 0.25 * k - 3.0;
      const double groove = (k % 4 == 0) ? -0.1 : 0.0;
      s.vertices.emplace_back(x, -11.0 + groove, z);
      s.colors.push_back(z < 0.0 ? 220.0f : 40.0f);
    }
  }
  for (int k = 0; k + 1 < nz; ++k) {
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = k * nx + i;
      // Normal (x along i) x (z along k) = -Y; wound the other way: +Y.
      s.triangles.emplace_back(a, a + nx + 1, a + 1);
      s.triangles.emplace_back(a, a + nx, a + nx + 1);
    }
  }
  return s;
}

// Mean textured grey of the surface pixels in the upper and the lower half of the right panel.
std::pair<double, double> UpperLowerGrey(const ImagePlanes& image, const PreviewOptions& o) {
  double sum[2] = {0, 0};
  long long count[2] = {0, 0};
  for (int y = 0; y < image.height; ++y) {
    for (int x = o.panel_width; x < 2 * o.panel_width; ++x) {
      bool background = true;
      for (int c = 0; c < 3; ++c) background = background && image.at(c, x, y) == o.background[c];
      if (background) continue;
      const int half = y < image.height / 2 ? 0 : 1;
      sum[half] += image.at(0, x, y);
      ++count[half];
    }
  }
  return {count[0] ? sum[0] / count[0] : 0.0, count[1] ? sum[1] / count[1] : 0.0};
}

// The products' preview of a facade: with the Z frame the wall is seen from behind and
// below, its shaded panel dark (ambient only) and upside down; the facade frame looks at
// its front with the cameras' up (here -Z) at the top and lights it.
TEST(Preview, FacadeIsSeenFromTheFrontWithTheCamerasUpOnTop) {
  const ExportSurface surface = Facade();
  PreviewOptions options;
  options.up = Eigen::Vector3d(0.02, -0.04, -1.0);  // the fountain's cameras: Z down
  const PreviewFrame frame = ChoosePreviewFrame(surface, options);
  EXPECT_TRUE(frame.facade);
  EXPECT_GT(frame.toward.y(), 0.8);   // in front of the wall (its normal is +Y)
  EXPECT_GT(frame.light.y(), 0.0);    // the light falls on the front
  EXPECT_LT(frame.vertical.z(), -0.99);
  PreviewOptions z_frame = options;
  z_frame.facade_frame = false;
  EXPECT_FALSE(ChoosePreviewFrame(surface, z_frame).facade);
  // The gable roof keeps the Z frame, whatever `up` says.
  EXPECT_FALSE(ChoosePreviewFrame(GableRoof(), options).facade);

  const ImagePlanes facade = Planes(RenderPreview(surface, options));
  const ImagePlanes old = Planes(RenderPreview(surface, z_frame));
  const PanelStats shaded = Panel(facade, 0, options.panel_width, options);
  const PanelStats shaded_old = Panel(old, 0, options.panel_width, options);
  const auto [upper, lower] = UpperLowerGrey(facade, options);
  const auto [upper_old, lower_old] = UpperLowerGrey(old, options);
  std::cout << "facade preview: shaded mean " << shaded.mean_surface_grey << " (Z frame " << shaded_old.mean_surface_grey
            << "), background " << shaded.background_share << " (Z frame " << shaded_old.background_share
            << "); textured upper / lower half " << upper << " / " << lower << " (Z frame " << upper_old << " / "
            << lower_old << ")\n";
  EXPECT_LT(shaded_old.mean_surface_grey, 60.0);  // ambient 0.15 * 255 = 38 where unlit
  EXPECT_GT(shaded.mean_surface_grey, 120.0);
  EXPECT_GT(upper, lower + 100.0);          // the top of the wall at the top of the picture
  EXPECT_LT(upper_old, lower_old - 100.0);  // the Z frame shows it upside down
  EXPECT_LT(shaded.background_share, 0.6);
  EXPECT_TRUE(shaded.border_is_background);
}

TEST(Preview, RejectsBadOptionsAndSurfaces) {
  ExportSurface surface = GableRoof();
  PreviewOptions options;
  options.view_elevation_deg = 90.0;
  EXPECT_THROW(RenderPreview(surface, options), std::invalid_argument);
  options = PreviewOptions();
  options.supersampling = 0;
  EXPECT_THROW(RenderPreview(surface, options), std::invalid_argument);
  surface.triangles.clear();
  try {
    RenderPreview(surface, PreviewOptions(), "x/preview.png");
    ADD_FAILURE() << "no triangles accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("x/preview.png"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace facets
