#include "io/image_subset.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <regex>
#include <set>
#include <stdexcept>
#include <unordered_set>

namespace facets {
namespace {

std::vector<int> EveryNth(const ImageBlock& block, int n) {
  std::vector<int> by_name(block.images.size());
  std::iota(by_name.begin(), by_name.end(), 0);
  std::sort(by_name.begin(), by_name.end(),
            [&](int a, int b) { return block.images[a].name < block.images[b].name; });
  std::vector<int> chosen;
  for (size_t position = n - 1; position < by_name.size(); position += n) {
    chosen.push_back(by_name[position]);
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

std::string Trimmed(const std::string& text) {
  const size_t first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  const size_t last = text.find_last_not_of(" \t\r");
  return text.substr(first, last - first + 1);
}

std::vector<std::string> NamesInFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("image list " + path + ": cannot open");
  std::vector<std::string> names;
  for (std::string line; std::getline(in, line);) {
    line = Trimmed(line);
    if (!line.empty() && line[0] != '#') names.push_back(line);
  }
  return names;
}

std::vector<std::string> NamesInList(const std::string& list) {
  std::vector<std::string> names;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t comma = std::min(list.find(',', start), list.size());
    const std::string name = Trimmed(list.substr(start, comma - start));
    if (!name.empty()) names.push_back(name);
    start = comma + 1;
  }
  return names;
}

}  // namespace

std::vector<int> SelectImages(const ImageBlock& block, const std::string& spec) {
  static const std::regex every(R"(every-(\d+)(st|nd|rd|th)?)");
  std::smatch match;
  if (std::regex_match(spec, match, every)) {
    const int n = std::stoi(match[1].str());
    if (n < 2) throw std::invalid_argument("image selection " + spec + ": N must be at least 2");
    return EveryNth(block, n);
  }
  const bool is_file = std::filesystem::is_regular_file(spec);
  const std::vector<std::string> names = is_file ? NamesInFile(spec) : NamesInList(spec);
  const std::string source = is_file ? "image list " + spec : "image selection '" + spec + "'";
  if (names.empty()) throw std::invalid_argument(source + ": names no image");
  std::map<std::string, int> index_of;
  for (size_t i = 0; i < block.images.size(); ++i) index_of[block.images[i].name] = static_cast<int>(i);
  std::set<int> chosen;
  for (const std::string& name : names) {
    const auto it = index_of.find(name);
    if (it == index_of.end()) {
      throw std::invalid_argument(source + ": no image named " + name + " in the model");
    }
    chosen.insert(it->second);
  }
  return {chosen.begin(), chosen.end()};
}

ImageBlock WithoutImages(const ImageBlock& block, const std::vector<int>& indices) {
  std::unordered_set<int> dropped_ids;
  for (int index : indices) dropped_ids.insert(block.images.at(index).image_id);
  ImageBlock kept = block;
  kept.images.clear();
  for (const BlockImage& image : block.images) {
    if (!dropped_ids.count(image.image_id)) kept.images.push_back(image);
  }
  kept.points.clear();
  for (const TiePoint& point : block.points) {
    TiePoint copy = point;
    copy.track.clear();
    for (const TrackElement& element : point.track) {
      if (!dropped_ids.count(element.image_id)) copy.track.push_back(element);
    }
    std::unordered_set<int> images;
    for (const TrackElement& element : copy.track) images.insert(element.image_id);
    if (images.size() >= 2 || point.track.empty()) kept.points.push_back(std::move(copy));
  }
  return kept;
}

std::string ImageNames(const ImageBlock& block, const std::vector<int>& indices) {
  std::string names;
  for (int index : indices) names += (names.empty() ? "" : ", ") + block.images.at(index).name;
  return names;
}

}  // namespace facets
