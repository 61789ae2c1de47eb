#include "io/colmap_io.h"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <vector>

#include "io/atomic_file.h"
#include "io/input_file.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

// One whitespace-separated line of a COLMAP text file. Numbers are parsed with
// std::from_chars, which never looks at a locale (a decimal comma locale cannot break
// it) and is several times faster than a stream on the 13 MB images.txt files.
class Line {
 public:
  Line(std::string_view text, const std::string& file, int line_number)
      : file_(file), line_number_(line_number) {
    size_t i = 0;
    while (i < text.size()) {
      while (i < text.size() && IsSpace(text[i])) ++i;
      const size_t start = i;
      while (i < text.size() && !IsSpace(text[i])) ++i;
      if (i > start) tokens_.push_back(text.substr(start, i - start));
    }
  }

  size_t size() const { return tokens_.size(); }
  std::string_view token(size_t i) const { return tokens_[i]; }

  [[noreturn]] void Fail(const std::string& message) const {
    throw std::runtime_error(file_ + ":" + std::to_string(line_number_) + ": " + message);
  }

  void ExpectAtLeast(size_t count, const std::string& what) const {
    if (tokens_.size() < count) {
      Fail("truncated line: " + what + " needs " + std::to_string(count) + " fields, got " +
           std::to_string(tokens_.size()));
    }
  }

  long long Integer(size_t i, const std::string& what) const {
    long long value = 0;
    const std::string_view t = tokens_.at(i);
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
    if (ec != std::errc() || end != t.data() + t.size()) {
      Fail(what + " is not an integer ('" + std::string(t) + "')");
    }
    return value;
  }

  int Int(size_t i, const std::string& what) const {
    const long long value = Integer(i, what);
    if (value < INT32_MIN || value > INT32_MAX) {
      Fail(what + " is out of range ('" + std::string(tokens_[i]) + "')");
    }
    return static_cast<int>(value);
  }

  // A finite double; NaN and inf are rejected with the field's name.
  double Finite(size_t i, const std::string& what) const {
    const double value = Double(i, what);
    if (!std::isfinite(value)) Fail(what + " is not finite ('" + std::string(tokens_[i]) + "')");
    return value;
  }

  double Double(size_t i, const std::string& what) const {
    double value = 0;
    const std::string_view t = tokens_.at(i);
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
    if (ec != std::errc() || end != t.data() + t.size()) {
      Fail(what + " is not a number ('" + std::string(t) + "')");
    }
    return value;
  }

 private:
  static bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

  const std::string& file_;
  int line_number_;
  std::vector<std::string_view> tokens_;
};

bool IsBlankOrComment(const std::string& text) {
  for (char c : text) {
    if (c == '#') return true;
    if (c != ' ' && c != '\t' && c != '\r') return false;
  }
  return true;
}

void ReadCameras(std::istream& in, const std::string& file, ImageBlock* block) {
  std::string text;
  int line_number = 0;
  while (std::getline(in, text)) {
    ++line_number;
    if (IsBlankOrComment(text)) continue;
    const Line line(text, file, line_number);
    line.ExpectAtLeast(4, "CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]");
    Camera camera;
    camera.camera_id = line.Int(0, "CAMERA_ID");
    const std::string model_name(line.token(1));
    try {
      camera.model = CameraModelFromName(model_name);
    } catch (const std::invalid_argument& e) {
      line.Fail(e.what());
    }
    camera.width = line.Int(2, "WIDTH");
    camera.height = line.Int(3, "HEIGHT");
    const size_t expected = CameraModelNumParams(camera.model);
    if (line.size() - 4 != expected) {
      line.Fail("camera model " + model_name + " needs " + std::to_string(expected) +
                " parameters, got " + std::to_string(line.size() - 4));
    }
    for (size_t i = 4; i < line.size(); ++i) {
      camera.params.push_back(line.Finite(i, "camera parameter " + std::to_string(i - 4)));
    }
    try {
      camera.Check();
    } catch (const std::invalid_argument& e) {
      line.Fail(e.what());
    }
    if (!block->cameras.emplace(camera.camera_id, camera).second) {
      line.Fail("duplicate CAMERA_ID " + std::to_string(camera.camera_id));
    }
  }
  if (in.bad()) throw std::runtime_error(file + ": read error");
  if (block->cameras.empty()) {
    throw std::runtime_error(file + ": is empty: no camera lines (only comments or blank lines)");
  }
}

void ReadImages(std::istream& in, const std::string& file, ImageBlock* block) {
  std::string text;
  int line_number = 0;
  std::set<int> ids;
  while (std::getline(in, text)) {
    ++line_number;
    if (IsBlankOrComment(text)) continue;
    const Line line(text, file, line_number);
    line.ExpectAtLeast(10, "IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME");
    BlockImage image;
    image.image_id = line.Int(0, "IMAGE_ID");
    const Eigen::Quaterniond q(line.Finite(1, "QW"), line.Finite(2, "QX"), line.Finite(3, "QY"),
                               line.Finite(4, "QZ"));
    if (!(q.norm() > 1e-6)) line.Fail("quaternion has (near) zero length");
    const Eigen::Vector3d t(line.Finite(5, "TX"), line.Finite(6, "TY"), line.Finite(7, "TZ"));
    image.cam_from_world = Rigid3d(q, t);
    image.camera_id = line.Int(8, "CAMERA_ID");
    // Names may contain spaces (COLMAP allows it): everything after CAMERA_ID.
    const std::string_view first = line.token(9);
    const std::string_view last = line.token(line.size() - 1);
    image.name = std::string(first.data(), last.data() + last.size() - first.data());
    if (!block->cameras.count(image.camera_id)) {
      line.Fail("image " + std::to_string(image.image_id) + " refers to unknown CAMERA_ID " +
                std::to_string(image.camera_id));
    }
    if (!ids.insert(image.image_id).second) {
      line.Fail("duplicate IMAGE_ID " + std::to_string(image.image_id));
    }
    // The second line (2D points) always follows, even when empty (COLMAP writes an
    // empty line for an image without features). A model cut after the header line of
    // its last image is accepted as having no 2D points there.
    if (std::getline(in, text)) {
      ++line_number;
      const Line points(text, file, line_number);
      if (points.size() % 3 != 0) {
        points.Fail("POINTS2D line of image " + std::to_string(image.image_id) +
                    " has " + std::to_string(points.size()) +
                    " fields, not a multiple of 3 (X Y POINT3D_ID)");
      }
      image.keypoints.resize(points.size() / 3);
      for (size_t k = 0; k < image.keypoints.size(); ++k) {
        Keypoint& keypoint = image.keypoints[k];
        keypoint.xy = {points.Finite(3 * k, "X of 2D point " + std::to_string(k)),
                       points.Finite(3 * k + 1, "Y of 2D point " + std::to_string(k))};
        keypoint.point3d_id =
            points.Integer(3 * k + 2, "POINT3D_ID of 2D point " + std::to_string(k));
      }
    }
    block->images.push_back(std::move(image));
  }
  if (in.bad()) throw std::runtime_error(file + ": read error");
  if (block->images.empty()) {
    throw std::runtime_error(file + ": is empty: no image lines (only comments or blank lines)");
  }
}

void ReadPoints(std::istream& in, const std::string& file, ImageBlock* block) {
  std::map<int, size_t> image_index;
  for (size_t i = 0; i < block->images.size(); ++i) {
    image_index[block->images[i].image_id] = i;
  }
  std::set<long long> ids;
  std::string text;
  int line_number = 0;
  while (std::getline(in, text)) {
    ++line_number;
    if (IsBlankOrComment(text)) continue;
    const Line line(text, file, line_number);
    line.ExpectAtLeast(8, "POINT3D_ID X Y Z R G B ERROR TRACK[]");
    if ((line.size() - 8) % 2 != 0) {
      line.Fail("TRACK has an odd number of fields (IMAGE_ID POINT2D_IDX pairs expected)");
    }
    TiePoint point;
    point.point3d_id = line.Integer(0, "POINT3D_ID");
    point.xyz = {line.Finite(1, "X"), line.Finite(2, "Y"), line.Finite(3, "Z")};
    point.rgb = {line.Int(4, "R"), line.Int(5, "G"), line.Int(6, "B")};
    point.error = line.Double(7, "ERROR");  // COLMAP writes -1 when unknown
    for (size_t i = 8; i < line.size(); i += 2) {
      TrackElement element;
      element.image_id = line.Int(i, "track IMAGE_ID");
      element.point2d_idx = line.Int(i + 1, "track POINT2D_IDX");
      const auto it = image_index.find(element.image_id);
      if (it == image_index.end()) {
        line.Fail("track refers to unknown IMAGE_ID " + std::to_string(element.image_id));
      }
      const auto& keypoints = block->images[it->second].keypoints;
      // Only checked when the image has 2D points at all: models written without them
      // (e.g. by a converter) still load.
      if (!keypoints.empty() &&
          (element.point2d_idx < 0 || element.point2d_idx >= static_cast<int>(keypoints.size()))) {
        line.Fail("track POINT2D_IDX " + std::to_string(element.point2d_idx) +
                  " out of range for image " + std::to_string(element.image_id) + " (" +
                  std::to_string(keypoints.size()) + " 2D points)");
      }
      point.track.push_back(element);
    }
    if (!ids.insert(point.point3d_id).second) {
      line.Fail("duplicate POINT3D_ID " + std::to_string(point.point3d_id));
    }
    block->points.push_back(std::move(point));
  }
  if (in.bad()) throw std::runtime_error(file + ": read error");
}

ImageBlock ReadModel(std::istream& cameras, const std::string& cameras_name,
                     std::istream& images, const std::string& images_name,
                     std::istream* points, const std::string& points_name) {
  ImageBlock block;
  ReadCameras(cameras, cameras_name, &block);
  ReadImages(images, images_name, &block);
  if (points) ReadPoints(*points, points_name, &block);
  return block;
}

// %.17g without printf's dependence on the C locale.
void AppendNumber(std::string* out, double value) {
  char buffer[40];
  const auto result =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::general, 17);
  out->append(buffer, result.ptr);
}

void AppendInt(std::string* out, long long value) {
  char buffer[24];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out->append(buffer, result.ptr);
}


}  // namespace

ImageBlock ReadColmapModel(std::istream& cameras, std::istream& images, std::istream* points,
                           const std::string& source_name) {
  return ReadModel(cameras, source_name + "/cameras.txt", images, source_name + "/images.txt",
                   points, source_name + "/points3D.txt");
}

ImageBlock ReadColmapModel(const std::string& sparse_dir, const std::string& image_dir) {
  const fs::path dir(sparse_dir);
  if (!fs::is_directory(dir)) {
    throw std::runtime_error(sparse_dir + ": COLMAP model folder does not exist");
  }
  const fs::path cameras_path = dir / "cameras.txt";
  const fs::path images_path = dir / "images.txt";
  const fs::path points_path = dir / "points3D.txt";
  if (!fs::exists(cameras_path) && fs::exists(dir / "cameras.bin")) {
    throw std::runtime_error(sparse_dir + ": holds a binary COLMAP model (cameras.bin); Facets reads "
                             "the text form: colmap model_converter --output_type TXT");
  }
  if (!image_dir.empty() && !fs::is_directory(image_dir)) {
    throw std::runtime_error(image_dir + ": image folder does not exist" +
                             (fs::exists(image_dir) ? " (it is a file)" : ""));
  }
  std::ifstream cameras = OpenInputFile(cameras_path.string(), "COLMAP cameras file");
  std::ifstream images = OpenInputFile(images_path.string(), "COLMAP images file");
  std::ifstream points;
  const bool has_points = fs::exists(points_path);
  if (has_points) points = OpenInputFile(points_path.string(), "COLMAP points file");
  ImageBlock block = ReadModel(cameras, cameras_path.string(), images, images_path.string(),
                               has_points ? &points : nullptr, points_path.string());
  if (!image_dir.empty()) {
    for (BlockImage& image : block.images) {
      const fs::path path = fs::path(image_dir) / image.name;
      if (!fs::is_regular_file(path)) {
        throw std::runtime_error(path.string() + ": image file of image " +
                                 std::to_string(image.image_id) + " (" + images_path.string() +
                                 ") not found");
      }
      image.path = path.string();
    }
  }
  return block;
}

namespace {

std::string CamerasText(const ImageBlock& block) {
  std::string cameras =
      "# Camera list with one line of data per camera:\n"
      "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      "# Number of cameras: ";
  AppendInt(&cameras, static_cast<long long>(block.cameras.size()));
  cameras += '\n';
  for (const auto& [id, camera] : block.cameras) {
    AppendInt(&cameras, id);
    cameras += ' ' + CameraModelName(camera.model) + ' ';
    AppendInt(&cameras, camera.width);
    cameras += ' ';
    AppendInt(&cameras, camera.height);
    for (double p : camera.params) {
      cameras += ' ';
      AppendNumber(&cameras, p);
    }
    cameras += '\n';
  }
  return cameras;
}

std::string ImagesText(const ImageBlock& block) {
  std::string images =
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      "# Number of images: ";
  AppendInt(&images, static_cast<long long>(block.images.size()));
  images += '\n';
  for (const BlockImage& image : block.images) {
    const Eigen::Quaterniond& q = image.cam_from_world.rotation;
    const Eigen::Vector3d& t = image.cam_from_world.translation;
    AppendInt(&images, image.image_id);
    for (double v : {q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z()}) {
      images += ' ';
      AppendNumber(&images, v);
    }
    images += ' ';
    AppendInt(&images, image.camera_id);
    images += ' ' + image.name + '\n';
    for (size_t k = 0; k < image.keypoints.size(); ++k) {
      if (k) images += ' ';
      AppendNumber(&images, image.keypoints[k].xy.x());
      images += ' ';
      AppendNumber(&images, image.keypoints[k].xy.y());
      images += ' ';
      AppendInt(&images, image.keypoints[k].point3d_id);
    }
    images += '\n';
  }
  return images;
}

std::string PointsText(const ImageBlock& block) {
  std::string points =
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: ";
  AppendInt(&points, static_cast<long long>(block.points.size()));
  points += '\n';
  for (const TiePoint& point : block.points) {
    AppendInt(&points, point.point3d_id);
    for (int i = 0; i < 3; ++i) {
      points += ' ';
      AppendNumber(&points, point.xyz[i]);
    }
    for (int i = 0; i < 3; ++i) {
      points += ' ';
      AppendInt(&points, point.rgb[i]);
    }
    points += ' ';
    AppendNumber(&points, point.error);
    for (const TrackElement& element : point.track) {
      points += ' ';
      AppendInt(&points, element.image_id);
      points += ' ';
      AppendInt(&points, element.point2d_idx);
    }
    points += '\n';
  }
  return points;
}

}  // namespace

void WriteColmapModel(const ImageBlock& block, const std::string& sparse_dir) {
  const fs::path dir(sparse_dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(sparse_dir + ": cannot create folder: " + ec.message());
  const std::string cameras = CamerasText(block);
  const std::string images = ImagesText(block);
  const std::string points = PointsText(block);
  WriteFileAtomically((dir / "cameras.txt").string(), cameras);
  WriteFileAtomically((dir / "images.txt").string(), images);
  WriteFileAtomically((dir / "points3D.txt").string(), points);
}

}  // namespace facets
