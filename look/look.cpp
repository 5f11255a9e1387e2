#include "look/look.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <unistd.h>

#include "core/json_file.h"
#include "core/json_message.h"
#include "look/parameters.h"
#include "look/user_error.h"

namespace darkroom {

using nlohmann::json;

namespace {

// The program's options that say how to run, not how the image looks.
bool is_run_option(const std::string& key) {
    for (const char* run : {"threads", "frame", "verbose", "look", "save-look"})
        if (key == run) return true;
    return false;
}

}  // namespace

json Look::to_json() const {
    json settings = json::object();
    for (const Parameter& p : parameters()) settings[p.key] = p.get(*this);
    return {{"format", kLookFormat}, {"version", kLookVersion}, {"settings", settings}};
}

namespace {

json number_schema(const Parameter& p) { return {{"type", "number"}, {"minimum", p.min}, {"maximum", p.max}}; }

json array_of(const json& items, int count) {
    return {{"type", "array"}, {"items", items}, {"minItems", count}, {"maxItems", count}};
}

// One setting's schema: its values, help and default.
json setting_schema(const Parameter& p) {
    json s;
    switch (p.type) {
        case ParameterType::stock:
        case ParameterType::text:
        case ParameterType::file: s = {{"type", {"string", "null"}}}; break;
        case ParameterType::number: s = number_schema(p); break;
        case ParameterType::per_channel:
            s = {{"oneOf", {number_schema(p), array_of(number_schema(p), 1), array_of(number_schema(p), 3)}}};
            if (p.stock_default) s["oneOf"].push_back({{"type", "null"}});
            break;
        case ParameterType::on_off: s = {{"type", "boolean"}}; break;
        case ParameterType::choice:
            s["enum"] = json::array();
            for (const Choice& c : p.choices) s["enum"].push_back(c.name);
            break;
        case ParameterType::seed:
            s = {{"type", "integer"}, {"minimum", 0}, {"maximum", std::numeric_limits<uint64_t>::max()}};
            break;
        case ParameterType::display_view: s = {{"oneOf", {{{"type", "null"}}, array_of({{"type", "string"}}, 2)}}}; break;
    }
    s["description"] = p.help + (p.unit.empty() ? "" : " (" + p.unit + ")");
    s["default"] = p.default_value();
    return s;
}

}  // namespace

json look_schema() {
    json settings = json::object();
    for (const Parameter& p : parameters()) settings[p.key] = setting_schema(p);
    return {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
            {"title", "Darkroom look"},
            {"description", "A look file: every setting of the look's parameter table, by key (look/parameters.h)"},
            {"type", "object"},
            {"required", {"format", "version"}},
            {"additionalProperties", false},
            {"properties",
             {{"format", {{"const", kLookFormat}}},
              {"version", {{"const", kLookVersion}}},
              {"settings", {{"type", "object"}, {"additionalProperties", false}, {"properties", settings}}}}}};
}

void apply_look_json(Look& look, const json& file, const std::string& source) {
    const std::string where = "look file '" + source + "'";
    // Compared as JSON values: a format of another type, or a version too large for an int,
    // is simply not this one.
    if (!file.is_object() || !file.contains("format") || file["format"] != kLookFormat)
        throw UserError(where + ": not a darkroom look (expected \"format\": \"" + kLookFormat + "\")");
    if (!file.contains("version") || !file["version"].is_number_integer() || file["version"] != kLookVersion)
        throw UserError(where + ": field 'version': this darkroom reads version " + std::to_string(kLookVersion) +
                        ", the file has " +
                        (file.contains("version") ? json_for_message(file["version"]) : std::string("none")));
    for (const auto& [key, value] : file.items())
        if (key != "format" && key != "version" && key != "settings")
            throw UserError(where + ": unknown field '" + key + "' (settings go under \"settings\")");
    if (!file.contains("settings")) return;
    if (!file["settings"].is_object()) throw UserError(where + ": field 'settings': expected an object");
    // Set on a copy: a file refused half-way changes nothing.
    Look read = look;
    for (const auto& [key, value] : file["settings"].items()) {
        const Parameter* p = find_parameter(key);
        if (!p && is_run_option(key))
            throw UserError(where + ", setting '" + key + "': a run option (how to run), not part of a look");
        if (!p) {
            const std::string near = closest_key(key);
            throw UserError(where + ", setting '" + key + "': unknown setting" +
                            (near.empty() ? "" : " (did you mean '" + near + "'?)"));
        }
        try {
            set_value(read, *p, value);
        } catch (const UserError& e) {
            throw UserError(where + ", setting '" + key + "': " + e.what());
        }
    }
    look = read;
}

void apply_look_text(Look& look, const std::string& text, const std::string& source) {
    json file;
    try {
        file = json::parse(text);
    } catch (const json::exception& e) {  // a syntax error, or a number too large for a double
        throw UserError("look file '" + source + "' is not valid JSON: " + e.what());
    }
    apply_look_json(look, file, source);
}

Look read_look_file(const std::string& path, const Look& base) {
    Look look = base;
    apply_look_text(look, read_json_file<UserError>(path, "look file"), path);
    return look;
}

void write_look_file(const std::string& path, const Look& look) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    std::error_code ec;
    const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
    if (!fs::is_directory(folder, ec)) throw UserError("cannot write look file '" + path + "': no folder " + folder.string());
    const fs::path temp = folder / (".darkroom-look-" + std::to_string(::getpid()) + "-" + target.filename().string());
    {
        std::ofstream out(temp, std::ios::binary | std::ios::trunc);
        out << look.to_json().dump(2) << "\n";
        out.close();
        if (!out) {
            fs::remove(temp, ec);
            throw UserError("cannot write look file '" + path + "'");
        }
    }
    fs::rename(temp, target, ec);
    if (ec) {
        const std::string why = ec.message();
        fs::remove(temp, ec);
        throw UserError("cannot write look file '" + path + "': " + why);
    }
}

}  // namespace darkroom
