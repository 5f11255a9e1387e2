#include "cli/look_flags.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "cli/user_error.h"

namespace darkroom::cli {

namespace {

using nlohmann::json;

// A number as the whole of a word ("1.5", "-2", "1e-3"); otherwise the word itself, for
// the table's check to refuse with its message.
json number_word(const std::string& word) {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(word.c_str(), &end);
    if (word.empty() || *end != '\0' || errno == ERANGE) return word;
    return v;
}

// A seed exactly, as an unsigned 64-bit integer; otherwise the word.
json seed_word(const std::string& word) {
    char* end = nullptr;
    errno = 0;
    const bool digits = !word.empty() && word.find_first_not_of("0123456789") == std::string::npos;
    const unsigned long long v = std::strtoull(word.c_str(), &end, 10);
    if (!digits || *end != '\0' || errno == ERANGE) return word;
    return uint64_t(v);
}

// A number as a person writes it: 25, 0.5, 1e+04.
std::string number_text(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// What --help shows of a setting: its help, unit and range.
std::string help_text(const Parameter& p) {
    std::string text = p.help;
    if (p.type == ParameterType::number || p.type == ParameterType::per_channel)
        text += " [" + number_text(p.min) + " to " + number_text(p.max) + (p.unit.empty() ? "" : " " + p.unit) + "]";
    return text;
}

std::string default_text(const Parameter& p) {
    const json d = p.default_value();
    if (d.is_null()) return p.stock_default ? "the stock's" : "";
    if (d.is_string()) return d.get<std::string>();
    if (d.is_number_float()) return number_text(d.get<double>());
    if (d.is_array() && p.type == ParameterType::per_channel) {
        std::string text = number_text(d[0].get<double>());
        if (d[0] != d[1] || d[1] != d[2]) text += "," + number_text(d[1].get<double>()) + "," + number_text(d[2].get<double>());
        return text;
    }
    return d.dump();
}

std::string choice_names(const Parameter& p) {
    std::string names;
    for (const Choice& c : p.choices) names += (names.empty() ? "" : "|") + c.name;
    return names;
}

// The words of one flag as the JSON value its parameter's check takes.
json flag_value(const Parameter& p, const std::vector<std::string>& words) {
    switch (p.type) {
        case ParameterType::number: return words.size() == 1 ? number_word(words[0]) : json(words);
        case ParameterType::per_channel: {
            json values = json::array();
            for (const std::string& w : words) values.push_back(number_word(w));
            return values.size() == 1 ? values[0] : values;
        }
        case ParameterType::on_off: return words.size() == 1 && words[0] == "true";
        case ParameterType::seed: return words.size() == 1 ? seed_word(words[0]) : json(words);
        case ParameterType::display_view: return words;
        default: return words.size() == 1 ? json(words[0]) : json(words);
    }
}

}  // namespace

Look LookFlags::look() const {
    Look l = look_path.empty() ? Look{} : read_look_file(look_path);
    for (const auto& [key, words] : given) {
        const Parameter& p = parameter(key);
        const json value = flag_value(p, words);
        try {
            set_value(l, p, value);
        } catch (const UserError& e) {
            // A word where a number goes does not convert; a number out of range is not accepted.
            const bool numeric = p.type == ParameterType::number || p.type == ParameterType::per_channel ||
                                 p.type == ParameterType::seed;
            const json& first = value.is_array() && !value.empty() ? value[0] : value;
            // (A seed of digits past 2^64 - 1 is a number out of range.)
            const bool word = first.is_string() && first.get<std::string>().find_first_not_of("0123456789") !=
                                                       std::string::npos;
            throw FlagValueError(p.cli_flag() + ": " + e.what(), numeric && word ? CLI::ExitCodes::ConversionError
                                                                                   : CLI::ExitCodes::ValidationError);
        }
    }
    return l;
}

void add_look_flags(CLI::App& cmd, LookFlags& flags, LookScope scope, bool with_frame) {
    for (const Parameter& p : parameters()) {
        if (scope == LookScope::per_pixel && !p.per_pixel) continue;
        const std::string key = p.key;
        auto remember = [&flags, key](const std::vector<std::string>& words) { flags.given[key] = words; };
        CLI::Option* option = nullptr;
        if (p.type == ParameterType::on_off) {
            option = cmd.add_flag_function(
                p.cli_flag() + ",!--no-" + key,
                [remember](std::int64_t count) { remember({count > 0 ? "true" : "false"}); }, help_text(p));
        } else {
            option = cmd.add_option_function<std::vector<std::string>>(p.cli_flag(), remember, help_text(p));
            if (p.type == ParameterType::per_channel)
                option->delimiter(',')->expected(1, 3)->type_name("X or " + p.channel_names[0] + "," +
                                                                   p.channel_names[1] + "," + p.channel_names[2]);
            else if (p.type == ParameterType::display_view)
                option->expected(2)->type_name("DISPLAY VIEW");
            else if (p.type == ParameterType::choice)
                option->expected(1)->type_name(choice_names(p));
            else
                option->expected(1)->type_name(p.type == ParameterType::number ? "NUMBER"
                                               : p.type == ParameterType::seed ? "UINT64"
                                               : p.type == ParameterType::file ? "FILE"
                                                                                : "TEXT");
        }
        option->default_str(default_text(p))->group(p.group);
    }
    cmd.add_option("--look", flags.look_path,
                   "Read the settings from a look file (JSON); flags on the command line override it");
    cmd.add_option("--save-look", flags.save_look_path,
                   "Write every look setting (given, from --look, or default) to a JSON look file");
    cmd.add_option("--threads", flags.threads, "Worker threads (0 = all cores; default $OPENIMAGEIO_THREADS or 0)")
        ->check(CLI::Range(0, 1024))
        ->envname("OPENIMAGEIO_THREADS");
    cmd.add_flag("-v,--verbose", flags.verbose,
                 "Print the plan (the stages run and those skipped) and the colour management");
    if (with_frame)
        flags.frame_option = cmd.add_option("--frame", flags.frame, "Frame number (each frame has its own grain)")
                                 ->capture_default_str();
}

}  // namespace darkroom::cli
