#include "cli/look_file.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "cli/atomic_file.h"
#include "cli/user_error.h"
#include "core/json_message.h"

namespace darkroom::cli {

namespace {

using nlohmann::json;

bool is_look_option(const CLI::Option* opt) {
    return opt->get_configurable() && !opt->get_lnames().empty();
}

// A string CLI11 holds, as the JSON value a person would write: true/false, a number, or text.
json to_json_value(const std::string& text, bool flag_like) {
    if (flag_like) return CLI::detail::to_flag_value(text) > 0;
    if (text.empty()) return text;
    char* end = nullptr;
    long long integer = std::strtoll(text.c_str(), &end, 10);
    if (*end == '\0') return integer;
    double number = std::strtod(text.c_str(), &end);
    if (*end == '\0' && std::isfinite(number)) return number;
    return text;
}

std::string to_input(const json& value, const std::string& where) {
    switch (value.type()) {
        case json::value_t::string: return value.get<std::string>();
        case json::value_t::boolean: return value.get<bool>() ? "true" : "false";
        case json::value_t::number_integer:
        case json::value_t::number_unsigned:
        case json::value_t::number_float: return value.dump();
        default:
            throw UserError(where + ": expected a string, number or true/false, got " + darkroom::json_for_message(value));
    }
}

// CLI11 writes a vector's default as "[a,b,c]".
std::vector<std::string> default_values(const CLI::Option* opt) {
    std::string text = opt->get_default_str();
    if (text.size() >= 2 && text.front() == '[' && text.back() == ']')
        return CLI::detail::split(text.substr(1, text.size() - 2), ',');
    if (text.empty()) return {};
    return {text};
}

std::vector<std::string> known_keys(const CLI::App& command) {
    std::vector<std::string> keys;
    for (const CLI::Option* opt : command.get_options())
        if (is_look_option(opt)) keys.push_back(opt->get_lnames().front());
    return keys;
}

}  // namespace

LookFileFlags add_look_file_flags(CLI::App& cmd, std::string& look_path, std::string& save_look_path) {
    LookFileFlags flags;
    flags.look = cmd.add_option("--look", look_path,
                                "Read the settings from a look file (JSON); flags on the command line override it")
                     ->configurable(false);
    flags.save_look = cmd.add_option("--save-look", save_look_path,
                                     "Write every look setting (given, from --look, or default) to a JSON look file")
                          ->configurable(false);
    return flags;
}

void apply_look(CLI::App& cmd, const json& look, const std::string& source) {
    // Compared as JSON values: a format of another type, or a version too large for an int,
    // is simply not this one.
    if (!look.is_object() || !look.contains("format") || look["format"] != kLookFormat)
        throw UserError("look file '" + source + "': not a darkroom look (expected \"format\": \"" + kLookFormat + "\")");
    if (!look.contains("version") || !look["version"].is_number_integer() || look["version"] != kLookVersion)
        throw UserError("look file '" + source + "': field 'version': this darkroom reads version " +
                        std::to_string(kLookVersion) + ", the file has " +
                        (look.contains("version") ? darkroom::json_for_message(look["version"]) : std::string("none")));
    for (const auto& [key, value] : look.items())
        if (key != "format" && key != "version" && key != "settings")
            throw UserError("look file '" + source + "': unknown field '" + key + "' (settings go under \"settings\")");
    if (!look.contains("settings")) return;
    if (!look["settings"].is_object())
        throw UserError("look file '" + source + "': field 'settings': expected an object");

    for (const auto& [key, value] : look["settings"].items()) {
        const std::string where = "look file '" + source + "', setting '" + key + "'";
        CLI::Option* opt = cmd.get_option_no_throw("--" + key);
        if (opt == nullptr)
            throw UserError(where + ": unknown setting (known: " + CLI::detail::join(known_keys(cmd), ", ") + ")");
        if (!is_look_option(opt)) throw UserError(where + ": '--" + key + "' is a run option, not part of a look");
        if (opt->count() > 0 || value.is_null()) continue;  // the command line wins; null: not set
        std::vector<std::string> inputs;
        if (value.is_array())
            for (const json& element : value) inputs.push_back(to_input(element, where));
        else
            inputs.push_back(to_input(value, where));
        if (inputs.empty()) throw UserError(where + ": an empty array (null leaves a setting unset)");
        try {
            if (opt->get_expected_min() == 0)  // a flag: true/false, possibly a negated one
                opt->add_result(opt->get_flag_value(key, inputs.front()));
            else
                opt->add_result(inputs);
            opt->run_callback();
        } catch (const CLI::Error& e) {
            throw UserError(where + ": " + e.what());
        }
    }
}

void apply_look_text(CLI::App& cmd, const std::string& text, const std::string& source) {
    json look;
    try {
        look = json::parse(text);
    } catch (const json::exception& e) {  // a syntax error, or a number too large for a double
        throw UserError("look file '" + source + "' is not valid JSON: " + e.what());
    }
    apply_look(cmd, look, source);
}

void apply_look_file(CLI::App& cmd, const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UserError("cannot open look file '" + path + "'");
    std::stringstream text;
    text << in.rdbuf();
    apply_look_text(cmd, text.str(), path);
}

json look_json(const CLI::App& cmd) {
    json settings = json::object();
    for (const CLI::Option* opt : cmd.get_options()) {
        if (!is_look_option(opt)) continue;
        const bool flag_like = opt->get_expected_min() == 0;
        std::vector<std::string> values = opt->count() > 0 ? opt->results() : default_values(opt);
        if (values.empty()) {  // no value and no default (an empty name): listed, as not set
            settings[opt->get_lnames().front()] = nullptr;
            continue;
        }
        if (flag_like && opt->count() > 0) values = {opt->as<bool>() ? "true" : "false"};
        json value;
        if (opt->get_expected_max() > 1 || values.size() > 1) {
            value = json::array();
            for (const std::string& v : values) value.push_back(to_json_value(v, false));
        } else {
            value = to_json_value(values.front(), flag_like);
        }
        settings[opt->get_lnames().front()] = value;
    }
    return {{"format", kLookFormat}, {"version", kLookVersion}, {"settings", settings}};
}

void save_look_file(const CLI::App& cmd, const std::string& path) {
    write_text_atomically(path, look_json(cmd).dump(2) + "\n");
}

}  // namespace darkroom::cli
