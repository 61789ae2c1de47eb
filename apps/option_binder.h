// Binds command-line options straight to the fields they set (CLI11), each option once,
// in one help group, and gives each option the value of its field in the form a --config
// file reads (Option::capture_default_str then returns it: the help's defaults, the
// settings.ini a run writes, the values a scene preset set).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "io/image_block.h"

namespace facets {

// A value as a --config file reads it back: doubles in their shortest exact form (so a
// settings.ini repeats a run bit for bit), lists as [a,b,c], an unset optional empty.
std::string ConfigText(double value);
std::string ConfigText(int value);
std::string ConfigText(bool value);
std::string ConfigText(const std::string& value);
std::string ConfigText(const std::optional<double>& value);
std::string ConfigText(const std::vector<double>& values);

// The region given on the command line as 6 numbers xmin ymin zmin xmax ymax zmax (m);
// throws naming `option` and the axis when a number is not finite or a min is not below
// its max (an empty or inverted region would silently select nothing).
RegionOfInterest RegionFromNumbers(const std::vector<double>& numbers, const std::string& option);

// A --config error the user can act on: the file, and for an unknown key the key, its
// section and the nearest known key of the subcommands' options (CLI11 says only "INI was
// not able to parse reconstruct.lamda").
std::string ConfigErrorMessage(const CLI::App& app, const std::string& file, const std::string& error);

// A --config value that its option refuses, with the file, the key and its section (CLI11
// says only "Could not convert: --levels = many"); "" when `error` is not about a value
// of the config file. Sets the options again from the file's values (the parse failed).
std::string ConfigValueErrorMessage(CLI::App& app, const CLI::ParseError& error);

class OptionBinder {
 public:
  OptionBinder(CLI::App* app, std::vector<CLI::Option*>* engine_options) : app_(app), engine_options_(engine_options) {}

  // The same binder with the options in help group `group` ("" hides them).
  OptionBinder InGroup(std::string group) const {
    OptionBinder copy = *this;
    copy.group_ = std::move(group);
    return copy;
  }
  // The same binder recording its options as engine options (they set fields of the
  // reconstruction's options, which a scene preset resets and the given options set again).
  OptionBinder Engine() const {
    OptionBinder copy = *this;
    copy.record_ = true;
    return copy;
  }

  // `--name VALUE` into `field`, its default shown.
  template <typename T>
  CLI::Option* Value(const std::string& name, T& field, const std::string& help) const {
    return Keep(app_->add_option(name, field, help)
                    ->default_function([&field] { return ConfigText(field); })
                    ->capture_default_str());
  }
  // `--name NAME` into an enum (or bool) field through the table of names.
  template <typename T>
  CLI::Option* Choice(const std::string& name, T& field, const std::vector<std::pair<std::string, T>>& names,
                      const std::string& help) const {
    std::string list;
    for (const auto& entry : names) list += (list.empty() ? "" : "|") + entry.first;
    auto text = [&field, names] {
      for (const auto& entry : names) {
        if (entry.second == field) return entry.first;
      }
      return std::string();
    };
    return Keep(app_->add_option(name, field, help)
                    ->transform(CLI::CheckedTransformer(names).description(""))
                    ->type_name(list)
                    ->default_function(text)
                    ->capture_default_str());
  }
  // A flag setting `field` true; `names` may add a negated name ("--x,!--no-x").
  CLI::Option* Switch(const std::string& names, bool& field, const std::string& help) const;
  // `--no-x`: sets `field` false.
  CLI::Option* Negative(const std::string& name, bool& field, const std::string& help) const;
  // "--x,!--no-x" into an optional switch (unset: the library decides).
  CLI::Option* OptionalSwitch(const std::string& names, std::optional<bool>& field, const std::string& help) const;
  // `--name VALUE` through a function that sets one or more fields; `value` gives the
  // option's current value ("" when it does not apply).
  template <typename T>
  CLI::Option* Function(const std::string& name, const std::function<void(const T&)>& set,
                        const std::function<std::string()>& value, const std::string& help) const {
    return Keep(app_->add_option_function<T>(name, set, help)->default_function(value)->capture_default_str());
  }

 private:
  CLI::Option* Keep(CLI::Option* option) const;

  CLI::App* app_;
  std::vector<CLI::Option*>* engine_options_;
  std::string group_;
  bool record_ = false;
};

}  // namespace facets
