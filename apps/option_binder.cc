#include "apps/option_binder.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include "io/input_file.h"

namespace facets {

std::string ConfigText(double value) {
  char text[32];
  const char* end = std::to_chars(text, text + sizeof(text), value).ptr;  // shortest exact form
  return std::string(text, static_cast<size_t>(end - text));
}
std::string ConfigText(int value) { return std::to_string(value); }
std::string ConfigText(bool value) { return value ? "true" : "false"; }
std::string ConfigText(const std::string& value) { return value; }
std::string ConfigText(const std::optional<double>& value) { return value ? ConfigText(*value) : std::string(); }
std::string ConfigText(const std::vector<double>& values) {
  if (values.empty()) return {};
  std::string text = "[";
  for (size_t i = 0; i < values.size(); ++i) text += (i > 0 ? "," : "") + ConfigText(values[i]);
  return text + "]";
}

RegionOfInterest RegionFromNumbers(const std::vector<double>& numbers, const std::string& option) {
  if (numbers.size() != 6) {
    throw std::invalid_argument(option + " takes 6 numbers: xmin ymin zmin xmax ymax zmax, got " +
                                std::to_string(numbers.size()));
  }
  RegionOfInterest roi;
  for (int axis = 0; axis < 3; ++axis) {
    const std::string name(1, "xyz"[axis]);
    roi.min[axis] = numbers[axis];
    roi.max[axis] = numbers[axis + 3];
    if (!std::isfinite(roi.min[axis]) || !std::isfinite(roi.max[axis])) {
      throw std::invalid_argument(option + ": " + name + "min or " + name + "max is not finite");
    }
    if (!(roi.min[axis] < roi.max[axis])) {
      throw std::invalid_argument(option + ": " + name + "min " + ConfigText(roi.min[axis]) + " is not below " +
                                  name + "max " + ConfigText(roi.max[axis]));
    }
  }
  return roi;
}

namespace {

// A key a --config file may hold: an option's long name in its subcommand's section.
struct ConfigKey {
  std::string section, name;
  std::string Text() const { return "'" + name + "' in [" + section + "]"; }
};

std::vector<ConfigKey> KnownConfigKeys(const CLI::App& app) {
  std::vector<ConfigKey> keys;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    for (const CLI::Option* option : sub->get_options()) {
      if (!option->get_configurable()) continue;
      for (const std::string& name : option->get_lnames()) keys.push_back({sub->get_name(), name});
    }
  }
  return keys;
}

// CLI11 names an unknown key "section.key", an unknown section "section.++", and a key
// outside any section by itself.
std::string UnknownConfigKey(const std::vector<ConfigKey>& known, const std::string& dotted) {
  const size_t dot = dotted.find('.');
  const std::string section = dot == std::string::npos ? "" : dotted.substr(0, dot);
  const std::string name = dot == std::string::npos ? dotted : dotted.substr(dot + 1);
  std::vector<std::string> sections;
  for (const ConfigKey& key : known) {
    if (std::find(sections.begin(), sections.end(), key.section) == sections.end()) sections.push_back(key.section);
  }
  if (name == "++") {
    return "unknown section [" + section + "] (nearest known section: [" + NearestName(section, sections) + "])";
  }
  // Within a known section its own keys; outside any or in an unknown one, every key.
  const bool known_section = std::find(sections.begin(), sections.end(), section) != sections.end();
  std::vector<std::string> names;
  std::vector<const ConfigKey*> keys;
  for (const ConfigKey& key : known) {
    if (known_section && key.section != section) continue;
    names.push_back(key.name);
    keys.push_back(&key);
  }
  std::string message = "unknown key '" + name + "' " + (section.empty() ? "outside any section" : "in [" + section + "]");
  const std::string nearest = NearestName(name, names);
  if (nearest.empty()) return message;
  const size_t at = static_cast<size_t>(std::find(names.begin(), names.end(), nearest) - names.begin());
  return message + " (nearest known key: " + keys[at]->Text() + ")";
}

}  // namespace

std::string ConfigErrorMessage(const CLI::App& app, const std::string& file, const std::string& error) {
  const std::string unknown = "INI was not able to parse ";
  if (error.rfind(unknown, 0) != 0) return "config file " + file + ": " + error;
  return "config file " + file + ": " + UnknownConfigKey(KnownConfigKeys(app), error.substr(unknown.size()));
}

// The config file's item whose value, handed to its option again, fails with `error`:
// CLI11 converts and checks a config value without saying where it came from.
std::string ConfigValueErrorMessage(CLI::App& app, const CLI::ParseError& error) {
  if (dynamic_cast<const CLI::ConversionError*>(&error) == nullptr &&
      dynamic_cast<const CLI::ValidationError*>(&error) == nullptr) {
    return "";
  }
  const std::vector<std::string> files = app.get_config_ptr()->results();
  if (files.empty() || files.front().empty()) return "";
  std::vector<CLI::ConfigItem> items;
  try {
    items = app.get_config_formatter()->from_file(files.front());
  } catch (const CLI::Error&) {
    return "";
  }
  for (const CLI::ConfigItem& item : items) {
    if (item.parents.size() != 1 || item.name == "++" || item.name == "--") continue;
    CLI::Option* option = nullptr;
    try {
      CLI::App* sub = app.get_subcommand(item.parents.front());
      option = sub->get_option_no_throw("--" + item.name);
      if (option == nullptr) option = sub->get_option_no_throw(item.name);
    } catch (const CLI::Error&) {
      continue;
    }
    if (option == nullptr) continue;
    try {  // as CLI11 reads a config item (App::_parse_single_config)
      option->clear();
      if (option->get_expected_min() == 0) {
        option->add_result(option->get_flag_value(item.name, app.get_config_formatter()->to_flag(item)));
      } else {
        option->add_result(item.inputs);
      }
      option->run_callback();
    } catch (const CLI::ParseError& again) {
      if (std::string(again.what()) != error.what()) continue;
      std::string value;
      for (const std::string& input : item.inputs) value += (value.empty() ? "" : " ") + input;
      return "config file " + files.front() + ": key '" + item.name + "' in [" + item.parents.front() +
             "]: bad value '" + value + "': " + error.what();
    } catch (const std::exception&) {
      continue;
    }
  }
  return "";
}

CLI::Option* OptionBinder::Keep(CLI::Option* option) const {
  option->group(group_);
  if (record_) engine_options_->push_back(option);
  return option;
}

CLI::Option* OptionBinder::Switch(const std::string& names, bool& field, const std::string& help) const {
  return Keep(app_->add_flag(names, field, help)->default_function([&field] { return ConfigText(field); }));
}

// A config file's `no-x = true` means the flag was given: the field's value negated.
CLI::Option* OptionBinder::Negative(const std::string& name, bool& field, const std::string& help) const {
  return Keep(app_->add_flag("!" + name, field, help)->default_function([&field] { return ConfigText(!field); }));
}

namespace {

// CLI11 sums a flag function's values with detail::to_flag_value, which throws
// std::invalid_argument or std::out_of_range (not a CLI::ParseError) on a value that is
// neither a switch word nor a number, as in `normal-search = " "` in a --config file.
CLI::Validator SwitchValue() {
  return CLI::Validator(
      [](std::string& value) -> std::string {
        try {
          CLI::detail::to_flag_value(value);
          return {};
        } catch (const std::exception&) {
          return "'" + value + "' is not a switch value (true, false, yes, no, on, off, 1, 0)";
        }
      },
      "SWITCH");
}

}  // namespace

CLI::Option* OptionBinder::OptionalSwitch(const std::string& names, std::optional<bool>& field,
                                          const std::string& help) const {
  auto set = [&field](std::int64_t count) { field = count > 0; };
  auto text = [&field] { return field ? ConfigText(*field) : std::string(); };
  return Keep(app_->add_flag_function(names, set, help)->default_function(text)->check(SwitchValue()));
}

}  // namespace facets
