// Test helper: a bundled or test scene rendered into a folder and read back as the
// block a user would give `facets reconstruct` (COLMAP model + images), with the
// scene's window as region of interest.
//
// Renders are cached on disk, once per test binary: ctest runs every test case in its own
// process, and several cases of a binary (and both ctest -j workers) ask for the same
// scene. The cache folder is FACETS_RENDER_CACHE (environment) or <build>/render-cache;
// an entry is keyed by the executable (path, size, modification time), the scene file's
// text and the render options, so a rebuilt test binary renders afresh and removes the
// entries its previous build left. An entry is rendered under a file lock into a private
// folder and renamed into place, so concurrent processes never see a half-written render.
//
// The cached folder is shared and read-only by contract: a test that changes images or
// writes files next to them copies the render first (CopyRender).
#pragma once

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

#include "io/colmap_io.h"
#include "io/image_block.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"

namespace facets {

struct RenderedScene {
  Scene scene;
  std::string dir;
  ImageBlock block;
};

// The render options that change the images or the tie points, as text.
inline std::string RenderOptionsKey(const RenderOptions& options) {
  std::string key;
  if (options.seed) key += " seed=" + std::to_string(*options.seed);
  if (options.noise_sigma) key += " noise=" + std::to_string(*options.noise_sigma);
  if (options.supersampling) key += " supersampling=" + std::to_string(*options.supersampling);
  return key;
}

namespace render_cache {

namespace fs = std::filesystem;

inline std::string FileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read scene file " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// FNV-1a, 64 bits: a stable key across processes (std::hash need not be).
inline std::uint64_t Fnv1a(const std::string& text) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return h;
}

// "path size mtime" of the running test binary: a rebuild changes it.
inline std::string ExecutableStamp() {
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  const auto mtime = fs::last_write_time(exe).time_since_epoch().count();
  return exe.string() + " " + std::to_string(fs::file_size(exe)) + " " + std::to_string(mtime);
}

inline fs::path Root() {
  if (const char* env = std::getenv("FACETS_RENDER_CACHE"); env != nullptr && *env) return env;
#ifdef FACETS_RENDER_CACHE_DIR
  return FACETS_RENDER_CACHE_DIR;
#else
  return fs::temp_directory_path() / "facets-render-cache";
#endif
}

// Removes entries an earlier build of this executable left (same path, other stamp).
inline void RemoveStaleEntries(const fs::path& root, const std::string& stamp) {
  const std::string exe = stamp.substr(0, stamp.find(' '));
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(root, ec)) {
    std::ifstream in(entry.path() / "made_by");
    std::string made_by;
    if (!in || !std::getline(in, made_by)) continue;
    if (made_by != stamp && made_by.substr(0, made_by.find(' ')) == exe) fs::remove_all(entry.path(), ec);
  }
}

// Holds an exclusive flock on `path` for the object's lifetime.
class FileLock {
 public:
  explicit FileLock(const fs::path& path) : fd_(::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644)) {
    if (fd_ < 0 || ::flock(fd_, LOCK_EX) != 0) throw std::runtime_error("cannot lock " + path.string());
  }
  ~FileLock() { ::close(fd_); }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_;
};

}  // namespace render_cache

// The folder holding `scene`, loaded unchanged from `scene_file` (its full path), rendered
// with `options`: from the disk cache, rendered into it first when absent.
inline std::string RenderSceneOnce(const std::string& scene_file, const Scene& scene,
                                   const RenderOptions& options = {}) {
  namespace fs = std::filesystem;
  const std::string stamp = render_cache::ExecutableStamp();
  const std::uint64_t key = render_cache::Fnv1a(stamp + "\n" + render_cache::FileText(scene_file) + "\n" +
                                                RenderOptionsKey(options));
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(key));
  const fs::path root = render_cache::Root();
  fs::create_directories(root);
  const fs::path folder = root / (fs::path(scene_file).stem().string() + "-" + hex);
  const render_cache::FileLock lock(folder.string() + ".lock");
  if (fs::exists(folder / "made_by")) return folder.string();
  render_cache::RemoveStaleEntries(root, stamp);
  // Under the lock, any other process's scratch folder for this entry is a dead render's.
  const std::string scratch_prefix = folder.filename().string() + ".rendering-";
  for (const auto& entry : fs::directory_iterator(root)) {
    if (entry.path().filename().string().rfind(scratch_prefix, 0) == 0) fs::remove_all(entry.path());
  }
  const fs::path scratch = root / (scratch_prefix + std::to_string(::getpid()));
  RenderScene(scene, scratch.string(), options);
  std::ofstream(scratch / "made_by") << stamp << "\n";
  fs::remove_all(folder);  // an entry without made_by: a render that died before the rename
  fs::rename(scratch, folder);
  return folder.string();
}

// A private, writable copy of a cached render in `dir` (replaced if present).
inline std::string CopyRender(const std::string& cached, const std::string& dir) {
  namespace fs = std::filesystem;
  fs::remove_all(dir);
  fs::copy(cached, dir, fs::copy_options::recursive);
  return dir;
}

// scene_file relative to the source tree, e.g. "scenes/data/seed_gable_parallel.json":
// the cached render (see above), read back once per process.
inline RenderedScene RenderAndRead(const std::string& scene_file) {
  static std::map<std::string, RenderedScene> rendered;  // scene file -> scene and block
  if (auto it = rendered.find(scene_file); it != rendered.end()) return it->second;
  const std::string path = std::string(FACETS_SOURCE_DIR) + "/" + scene_file;
  RenderedScene r;
  r.scene = LoadScene(path);
  r.dir = RenderSceneOnce(path, r.scene);
  r.block = ReadColmapModel(r.dir + "/sparse", r.dir + "/images");
  r.block.roi = r.scene.roi;
  return rendered.emplace(scene_file, r).first->second;
}

}  // namespace facets
