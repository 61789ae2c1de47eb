#include "apps/option_binder.h"

#include <charconv>

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

CLI::Option* OptionBinder::OptionalSwitch(const std::string& names, std::optional<bool>& field,
                                          const std::string& help) const {
  auto set = [&field](std::int64_t count) { field = count > 0; };
  auto text = [&field] { return field ? ConfigText(*field) : std::string(); };
  return Keep(app_->add_flag_function(names, set, help)->default_function(text));
}

}  // namespace facets
