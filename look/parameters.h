// The parameter table: one row per look setting, with everything a front end needs to offer
// it (type, unit, default, range, help, group, animatable) and its name in each (look-file
// key, program flag, OpenFX parameter, Python keyword). The program's flags, the plugin's
// parameters, the Python keywords and look files are all made from this table, so a setting
// added here appears everywhere with the same default, range and meaning.
//
// Names: the look-file key is the row's key ("print-exposure"); the flag is "--" + key and
// the Python keyword the key with '_' for '-' ("print_exposure"); the OpenFX name is the
// row's own (camel case, as hosts' scripts and saved projects know them: "printExposure").
#pragma once

#include <array>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/stock.h"
#include "look/look.h"

namespace darkroom {

enum class ParameterType {
    stock,         // a built-in stock id or a stock file's path
    text,          // a string, "" for the default
    file,          // a file's path, "" for none
    number,        // a real within [min, max]
    per_channel,   // three reals within [min, max] (R, G, B or Y, M, C); one value sets all
    on_off,        // true or false
    choice,        // one of `choices`, by name
    seed,          // an unsigned 64-bit integer
    display_view,  // an OCIO display and view (two strings), or none
};

struct Choice {
    std::string name;   // in look files, flags and Python
    std::string label;  // what the plugin shows
};

struct Parameter {
    std::string key;
    ParameterType type = ParameterType::number;
    std::string unit;   // "EV", "points", "CC", "mm", or ""
    std::string group;  // the plugin's group of parameters
    std::string label;  // the plugin's label
    std::string help;
    double min = 0, max = 0;                  // number, per_channel: the accepted values
    double display_min = 0, display_max = 0;  // the plugin's slider
    bool animatable = false;
    // Unset (null) means the stock's own value (per_channel): the plugin offers an override.
    bool stock_default = false;
    double override_start = 0;  // (stock_default) the value an override starts at
    // Changes a pixel's colour by itself, so a LUT holds it (bake-lut's flags); grain, seed,
    // MTF, halation and the formats do not.
    bool per_pixel = false;
    std::string ofx_name;                      // empty: not a plugin parameter
    std::vector<Choice> choices;               // choice
    std::array<std::string, 3> channel_names;  // per_channel: "R", "G", "B" or "Y", "M", "C"
    std::vector<StockKind> stock_kinds;        // stock: the kinds it takes

    // The value in `look`, as a look file holds it; and setting it from a value that
    // check_value accepted.
    std::function<nlohmann::json(const Look&)> get;
    std::function<void(Look&, const nlohmann::json&)> set;

    std::string cli_flag() const { return "--" + key; }
    std::string python_keyword() const;
    // The default: the value in a default Look.
    nlohmann::json default_value() const { return get(Look{}); }
};

// Every look setting, in the order front ends list them.
const std::vector<Parameter>& parameters();
// The row with this look-file key; null when there is none.
const Parameter* find_parameter(const std::string& key);
const Parameter& parameter(const std::string& key);  // (one that must exist)

// The value a setting takes from `value`, in its canonical form (a per-channel setting's
// one value repeated, a choice's name as the table spells it); throws UserError saying what
// the value must be ("must be a number from -64 to 64, not 70"), without naming the setting.
nlohmann::json check_value(const Parameter& p, const nlohmann::json& value);
// check_value, then set.
void set_value(Look& look, const Parameter& p, const nlohmann::json& value);

// The output mode's name, as the table spells it ("print").
std::string output_name(OutputMode mode);

// How a front end names a setting in messages: its flag, its plugin label, its keyword.
using Naming = std::function<std::string(const Parameter&)>;
std::string flag_name(const Parameter& p);      // "--print-exposure"
std::string ofx_label(const Parameter& p);      // "Print exposure (EV)"
std::string python_name(const Parameter& p);    // "print_exposure="
std::string look_file_key(const Parameter& p);  // "'print-exposure'"

// The checks that span settings (print output needs a paper; a display excludes an output
// colour space; densities are not colours), naming the settings with `name`.
void validate(const Look& look, const Naming& name);

// The closest key to a misspelt one, for "did you mean"; empty when none is close.
std::string closest_key(const std::string& key);

}  // namespace darkroom
