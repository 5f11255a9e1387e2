#include "plugin/parameters.h"

#include <array>
#include <climits>
#include <cmath>
#include <vector>

#include "look/parameters.h"
#include "look/user_error.h"
#include "plugin/ofx_host.h"

namespace darkroom::ofx {

namespace {

using nlohmann::json;

// The table's groups as the node's group parameters, in order; and the node's own.
struct Group {
    const char* label;
    const char* name;
    bool open;
};
constexpr const char* kLookGroup = "lookGroup";
const std::array<Group, 6> kGroups{{{"Stocks", "stocksGroup", true},
                                    {"Exposure and printing", "exposureGroup", true},
                                    {"Grain", "grainGroup", true},
                                    {"Development", "developmentGroup", false},
                                    {"Optics and format", "opticsGroup", false},
                                    {"Colour management (OCIO)", "colourGroup", false}}};

const char* group_name(const Parameter& p) {
    for (const Group& g : kGroups)
        if (p.group == g.label) return g.name;
    throw std::logic_error("the plugin has no group for '" + p.group + "'");
}

// The node's own parameters (script names).
constexpr const char* kLookFile = "lookFile";
constexpr const char* kLoadLook = "loadLook";
constexpr const char* kSaveLook = "saveLook";
constexpr const char* kStaticGrain = "staticGrain";
constexpr const char* kFilmFrame = "filmFrame";

// The names of the parameters a row makes besides its own (see define_row).
std::string file_param(const Parameter& p) { return p.ofx_name + "File"; }      // stock: a stock file
std::string id_param(const Parameter& p) { return p.ofx_name + "Stock"; }       // stock: the chosen id
std::string override_param(const Parameter& p) { return p.ofx_name + "Override"; }  // per-channel
std::string display_param(const Parameter& p) { return p.ofx_name + "Display"; }
std::string view_param(const Parameter& p) { return p.ofx_name + "View"; }

// An option of a stock choice: what it stands for (a built-in stock's id, or one of the
// two below) and what the user sees.
struct StockOption {
    std::string id, label;
};
constexpr const char* kStockFileId = "file";
constexpr const char* kNoPaperId = "none";

const char* role_label(StockKind kind) {
    switch (kind) {
        case StockKind::negative: return "Negative";
        case StockKind::reversal: return "Reversal";
        case StockKind::print_film: return "Print film";
        case StockKind::paper: return "Paper";
    }
    return "";
}

// The built-in stocks of the row's kinds by role, then none (a print stage's row) and a file.
std::vector<StockOption> stock_options(const Parameter& p) {
    std::vector<StockOption> options;
    for (StockKind kind : p.stock_kinds)
        for (const Stock& s : builtin_stocks())
            if (s.kind == kind) options.push_back({s.id, std::string(role_label(kind)) + ": " + s.name});
    if (p.stock_kinds.front() != StockKind::negative) options.push_back({kNoPaperId, "None (stop at the negative)"});
    options.push_back({kStockFileId, "Stock file..."});
    return options;
}

int option_index(const std::vector<StockOption>& options, const std::string& id) {
    for (size_t i = 0; i < options.size(); ++i)
        if (options[i].id == id) return int(i);
    return -1;
}

Props define(OfxParamSetHandle params, const char* type, const std::string& name, const std::string& label,
             const std::string& hint, const char* parent) {
    OfxPropertySetHandle h = nullptr;
    check(suites.param->paramDefine(params, type, name.c_str(), &h), ("defining parameter " + name).c_str());
    Props p(h);
    p.set(kOfxPropLabel, label);
    p.set(kOfxParamPropScriptName, name);
    if (!hint.empty()) p.set(kOfxParamPropHint, hint);
    if (parent) p.set(kOfxParamPropParent, parent);
    return p;
}

void define_bool(OfxParamSetHandle params, const std::string& name, const std::string& label, const std::string& hint,
                 const char* parent, bool def) {
    Props p = define(params, kOfxParamTypeBoolean, name, label, hint, parent);
    p.set(kOfxParamPropDefault, def ? 1 : 0);
    p.set(kOfxParamPropAnimates, 0);
}

void define_choice(OfxParamSetHandle params, const std::string& name, const std::string& label,
                   const std::string& hint, const char* parent, const std::vector<std::string>& options, int def) {
    Props p = define(params, kOfxParamTypeChoice, name, label, hint, parent);
    p.set(kOfxParamPropChoiceOption, options);
    p.set(kOfxParamPropDefault, def);
    p.set(kOfxParamPropAnimates, 0);
}

void define_string(OfxParamSetHandle params, const std::string& name, const std::string& label,
                   const std::string& hint, const char* parent, const std::string& def, bool file_path,
                   bool file_exists = true) {
    Props p = define(params, kOfxParamTypeString, name, label, hint, parent);
    p.set(kOfxParamPropDefault, def);
    p.set(kOfxParamPropStringMode, file_path ? kOfxParamStringIsFilePath : kOfxParamStringIsSingleLine);
    if (file_path) p.set(kOfxParamPropStringFilePathExists, file_exists ? 1 : 0);
    p.set(kOfxParamPropAnimates, 0);
}

// A real or three (one per channel or filter): the row's default, range and slider.
void define_doubles(OfxParamSetHandle params, const Parameter& row, const char* parent, const json& def) {
    const bool three = row.type == ParameterType::per_channel;
    Props p = define(params, three ? kOfxParamTypeDouble3D : kOfxParamTypeDouble, row.ofx_name, row.label, row.help,
                     parent);
    p.set(kOfxParamPropDoubleType, kOfxParamDoubleTypePlain);
    for (int i = 0; i < (three ? 3 : 1); ++i) {
        p.set(kOfxParamPropDefault, def.is_array() ? def[size_t(i)].get<double>() : def.get<double>(), i);
        p.set(kOfxParamPropMin, row.min, i);
        p.set(kOfxParamPropMax, row.max, i);
        p.set(kOfxParamPropDisplayMin, row.display_min, i);
        p.set(kOfxParamPropDisplayMax, row.display_max, i);
        if (three) p.set(kOfxParamPropDimensionLabel, row.channel_names[size_t(i)], i);
    }
    p.set(kOfxParamPropAnimates, row.animatable ? 1 : 0);
}

// One row of the table as the node's parameters.
void define_row(OfxParamSetHandle params, const Parameter& row) {
    const char* parent = group_name(row);
    const json def = row.default_value();
    switch (row.type) {
        case ParameterType::stock: {
            const auto options = stock_options(row);
            std::vector<std::string> labels;
            for (const StockOption& o : options) labels.push_back(o.label);
            define_choice(params, row.ofx_name, row.label, row.help, parent, labels,
                          option_index(options, def.get<std::string>()));
            define_string(params, file_param(row), row.label + " stock file",
                          "A Darkroom stock file (.json), used when " + row.label + " is 'Stock file'", parent, "",
                          true);
            // Empty until the node is created (restore_stock_choices), as in nodes saved before them.
            define_string(params, id_param(row), id_param(row), "The id of the stock chosen above, saved with the node",
                          parent, "", false);
            break;
        }
        case ParameterType::number: define_doubles(params, row, parent, def); break;
        case ParameterType::per_channel:
            if (row.stock_default) {
                define_bool(params, override_param(row), "Override " + row.label,
                            "Use " + row.label + " below instead of the stock's own", parent, false);
                define_doubles(params, row, parent, json(row.override_start));
            } else {
                define_doubles(params, row, parent, def);
            }
            break;
        case ParameterType::on_off: define_bool(params, row.ofx_name, row.label, row.help, parent, def.get<bool>()); break;
        case ParameterType::choice: {
            std::vector<std::string> labels;
            int index = 0;
            for (size_t i = 0; i < row.choices.size(); ++i) {
                labels.push_back(row.choices[i].label);
                if (row.choices[i].name == def) index = int(i);
            }
            define_choice(params, row.ofx_name, row.label, row.help, parent, labels, index);
            break;
        }
        case ParameterType::seed: {
            // A host's integer parameter holds 0 to 2^31 - 1 of the look's 64-bit seeds.
            Props seed = define(params, kOfxParamTypeInteger, row.ofx_name, row.label, row.help, parent);
            seed.set(kOfxParamPropDefault, int(def.get<uint64_t>()));
            seed.set(kOfxParamPropMin, 0);
            seed.set(kOfxParamPropMax, INT_MAX);
            seed.set(kOfxParamPropDisplayMin, 0);
            seed.set(kOfxParamPropDisplayMax, 1000);
            seed.set(kOfxParamPropAnimates, 0);
            break;
        }
        case ParameterType::text:
        case ParameterType::file:
            define_string(params, row.ofx_name, row.label, row.help, parent, "", row.type == ParameterType::file);
            break;
        case ParameterType::display_view:
            define_bool(params, row.ofx_name, row.label, row.help, parent, false);
            define_string(params, display_param(row), "Display", "The OCIO display (empty: the config's default)",
                          parent, "", false);
            define_string(params, view_param(row), "View", "The display's view (empty: its default)", parent, "",
                          false);
            break;
    }
}

// Reading and setting values of an instance.
class Reader {
public:
    Reader(OfxImageEffectHandle instance, OfxTime time) : time_(time) {
        check(suites.effect->getParamSet(instance, &params_), "getting the parameter set");
    }

    double get_double(const std::string& name) const {
        double v = 0;
        check(suites.param->paramGetValueAtTime(handle(name), time_, &v), name.c_str());
        return v;
    }
    std::array<double, 3> get_double3(const std::string& name) const {
        std::array<double, 3> v{};
        check(suites.param->paramGetValueAtTime(handle(name), time_, &v[0], &v[1], &v[2]), name.c_str());
        return v;
    }
    int get_int(const std::string& name) const {
        int v = 0;
        check(suites.param->paramGetValueAtTime(handle(name), time_, &v), name.c_str());
        return v;
    }
    bool get_bool(const std::string& name) const { return get_int(name) != 0; }
    std::string get_string(const std::string& name) const {
        char* v = nullptr;
        check(suites.param->paramGetValueAtTime(handle(name), time_, &v), name.c_str());
        return v ? v : "";
    }
    // The label the user sees, for messages.
    std::string label(const std::string& name) const {
        OfxPropertySetHandle props = nullptr;
        OfxParamHandle h = nullptr;
        if (suites.param->paramGetHandle(params_, name.c_str(), &h, &props) != kOfxStatOK || !props) return name;
        return Props(props).get_string_or(kOfxPropLabel, name);
    }
    int checked_choice(const std::string& name, int option_count) const {
        int v = get_int(name);
        if (v < 0 || v >= option_count)
            throw ParameterError(label(name) + " is option " + std::to_string(v) + ", which does not exist (0 to " +
                                 std::to_string(option_count - 1) + ")");
        return v;
    }
    // The id of the option a stock choice is set to. A node saved with a stock this version
    // does not have keeps that stock's id (restore_stock_choices) until the user chooses.
    std::string stock_choice(const Parameter& row) const {
        const auto options = stock_options(row);
        const std::string saved = get_string(id_param(row));
        if (!saved.empty() && option_index(options, saved) < 0)
            throw ParameterError(row.label + ": this node was saved with the stock '" + saved +
                                 "', which this version of Darkroom does not have; choose another");
        return options[size_t(checked_choice(row.ofx_name, int(options.size())))].id;
    }

    OfxParamHandle handle(const std::string& name) const {
        OfxParamHandle h = nullptr;
        check(suites.param->paramGetHandle(params_, name.c_str(), &h, nullptr), name.c_str());
        return h;
    }
    void set_int(const std::string& name, int v) const { check(suites.param->paramSetValue(handle(name), v), name.c_str()); }
    void set_double(const std::string& name, double v) const {
        check(suites.param->paramSetValue(handle(name), v), name.c_str());
    }
    void set_double3(const std::string& name, const json& v) const {
        check(suites.param->paramSetValue(handle(name), v[0].get<double>(), v[1].get<double>(), v[2].get<double>()),
              name.c_str());
    }
    void set_string(const std::string& name, const std::string& v) const {
        check(suites.param->paramSetValue(handle(name), v.c_str()), name.c_str());
    }

private:
    OfxParamSetHandle params_ = nullptr;
    OfxTime time_;
};

// A row's value at the reader's time, as the table's check takes it.
json row_value(const Reader& r, const Parameter& row, NodeSettings& n) {
    const std::string& name = row.ofx_name;
    switch (row.type) {
        case ParameterType::stock: {
            const bool print_stage = row.stock_kinds.front() != StockKind::negative;
            try {
                const std::string id = r.stock_choice(row);
                if (id != kStockFileId) return id;
                const std::string path = r.get_string(file_param(row));
                if (path.empty())
                    throw ParameterError(row.label + " is set to a stock file, but " + r.label(file_param(row)) +
                                         " is empty");
                (print_stage ? n.paper_from_file : n.film_from_file) = true;
                return path;
            } catch (const ParameterError&) {
                // Only the print output uses a paper: a paper it cannot use matters only then.
                if (print_stage && n.look.settings.output != OutputMode::print) return kNoPaperId;
                throw;
            }
        }
        case ParameterType::number: return r.get_double(name);
        case ParameterType::per_channel:
            if (row.stock_default && !r.get_bool(override_param(row))) return nullptr;
            return r.get_double3(name);
        case ParameterType::on_off: return r.get_bool(name);
        case ParameterType::choice: return row.choices[size_t(r.checked_choice(name, int(row.choices.size())))].name;
        case ParameterType::seed: {
            const int seed = r.get_int(name);
            return seed < 0 ? json(seed) : json(uint64_t(seed));
        }
        case ParameterType::text:
        case ParameterType::file: return r.get_string(name);
        case ParameterType::display_view:
            if (!r.get_bool(name)) return nullptr;
            return json::array({r.get_string(display_param(row)), r.get_string(view_param(row))});
    }
    return nullptr;
}

// The stock option a look's stock is: its id, none, or a file.
std::string stock_option_of(const Parameter& row, const std::string& stock) {
    if (option_index(stock_options(row), stock) >= 0) return stock;
    return kStockFileId;
}

// Sets a row's parameters to a look's value (the Load look button).
void set_row(const Reader& r, const Parameter& row, const json& value) {
    const std::string& name = row.ofx_name;
    switch (row.type) {
        case ParameterType::stock: {
            const std::string stock = value.get<std::string>();
            const std::string option = stock_option_of(row, stock);
            r.set_int(name, option_index(stock_options(row), option));
            r.set_string(id_param(row), option);
            if (option == kStockFileId) r.set_string(file_param(row), stock);
            break;
        }
        case ParameterType::number: r.set_double(name, value.get<double>()); break;
        case ParameterType::per_channel:
            if (row.stock_default) r.set_int(override_param(row), value.is_null() ? 0 : 1);
            if (!value.is_null()) r.set_double3(name, value);
            break;
        case ParameterType::on_off: r.set_int(name, value.get<bool>() ? 1 : 0); break;
        case ParameterType::choice:
            for (size_t i = 0; i < row.choices.size(); ++i)
                if (row.choices[i].name == value) r.set_int(name, int(i));
            break;
        case ParameterType::seed:
            if (value.get<uint64_t>() > uint64_t(INT_MAX))
                throw ParameterError(row.label + ": the look's seed " + value.dump() +
                                     " is larger than a host's integer parameter holds (2147483647)");
            r.set_int(name, int(value.get<uint64_t>()));
            break;
        case ParameterType::text:
        case ParameterType::file: r.set_string(name, value.get<std::string>()); break;
        case ParameterType::display_view:
            r.set_int(name, value.is_null() ? 0 : 1);
            if (!value.is_null()) {
                r.set_string(display_param(row), value[0].get<std::string>());
                r.set_string(view_param(row), value[1].get<std::string>());
            }
            break;
    }
}

std::string look_file_path(const Reader& r) {
    const std::string path = r.get_string(kLookFile);
    if (path.empty()) throw ParameterError(r.label(kLookFile) + " is empty: give the look file's path");
    return path;
}

// The Load look button: every row's parameters set to the file's look.
void load_look(OfxImageEffectHandle instance, OfxTime time) {
    const Reader r(instance, time);
    const std::string path = look_file_path(r);
    Look look;
    try {
        look = read_look_file(path);
    } catch (const UserError& e) {
        throw ParameterError(e.what());
    }
    // The node's choice of the stock comes first, so that what follows it (a paper's choice
    // read only for the print output) is set in a consistent state.
    for (const Parameter& row : parameters())
        if (!row.ofx_name.empty()) set_row(r, row, row.get(look));
}

// The Save look button: the node's look at `time` to the file.
void save_look(OfxImageEffectHandle instance, OfxTime time) {
    const Reader r(instance, time);
    const std::string path = look_file_path(r);
    const NodeSettings n = read_parameters(instance, time);
    try {
        write_look_file(path, n.look);
    } catch (const UserError& e) {
        throw ParameterError(e.what());
    }
}

// The choice set to the option with this id, when one has it.
void set_choice_to(OfxImageEffectHandle instance, const Parameter& row, const std::string& id) {
    const int index = option_index(stock_options(row), id);
    const Reader r(instance, 0);
    if (index >= 0 && r.get_int(row.ofx_name) != index) r.set_int(row.ofx_name, index);
}

// The id parameter set to the option the choice shows.
void record_choice(OfxImageEffectHandle instance, const Parameter& row) {
    const auto options = stock_options(row);
    const Reader r(instance, 0);
    const int index = r.get_int(row.ofx_name);
    if (index < 0 || index >= int(options.size())) return;  // read_parameters reports it
    r.set_string(id_param(row), options[size_t(index)].id);
}

template <typename F>
void each_stock_row(F&& f) {
    for (const Parameter& row : parameters())
        if (row.type == ParameterType::stock && !row.ofx_name.empty()) f(row);
}

}  // namespace

void define_parameters(OfxParamSetHandle params) {
    Props look_group = define(params, kOfxParamTypeGroup, kLookGroup, "Look file", "", nullptr);
    look_group.set(kOfxParamPropGroupOpen, 0);
    define_string(params, kLookFile, "Look file",
                  "A Darkroom look (.json): Load look sets the node's parameters from it; Save look writes them to it "
                  "(the program's --look and Python's look= read it)",
                  kLookGroup, "", true, false);
    define(params, kOfxParamTypePushButton, kLoadLook, "Load look", "Set the parameters from the Look file", kLookGroup);
    define(params, kOfxParamTypePushButton, kSaveLook, "Save look", "Write the parameters to the Look file",
           kLookGroup);
    const char* last_group = nullptr;
    for (const Parameter& row : parameters()) {
        if (row.ofx_name.empty()) continue;
        const char* group = group_name(row);
        if (!last_group || std::string(group) != last_group) {
            for (const Group& g : kGroups)
                if (group == std::string(g.name))
                    define(params, kOfxParamTypeGroup, g.name, g.label, "", nullptr).set(kOfxParamPropGroupOpen, g.open ? 1 : 0);
            last_group = group;
        }
        define_row(params, row);
        // The node's own, beside the settings they go with.
        if (row.key == "seed")
            define_bool(params, kStaticGrain, "Static grain", "The same grain on every frame (frame 0's)", group, false);
        if (row.key == "print-width-mm")
            define_choice(params, kFilmFrame, "Film frame",
                          "What the frame width spans: the project's format (a CG element's bounding box or overscan "
                          "is that part of the frame), or the Source image itself (a plate whose format differs from "
                          "the project's)",
                          group, {"Project format", "Source image"}, 0);
    }
}

NodeSettings read_parameters(OfxImageEffectHandle instance, OfxTime time) {
    const Reader r(instance, time);
    NodeSettings n;
    // The output first: whether the paper is read depends on it.
    std::vector<const Parameter*> rows{&parameter("output")};
    for (const Parameter& row : parameters())
        if (!row.ofx_name.empty() && row.key != "output") rows.push_back(&row);
    for (const Parameter* row : rows) {
        try {
            set_value(n.look, *row, row_value(r, *row, n));
        } catch (const UserError& e) {
            throw ParameterError(row->label + ": " + e.what());
        }
    }
    // Grain belongs to whole frames: a fractional (motion-blur) time uses its nearest frame.
    if (!std::isfinite(time) || std::abs(time) > 1e9) throw ParameterError("the host asked for time " + std::to_string(time));
    n.frame = r.get_bool(kStaticGrain) ? 0 : (int)std::lround(time);
    n.look.settings.frame = n.frame;
    n.film_frame_is_source = r.checked_choice(kFilmFrame, 2) == 1;
    return n;
}

void restore_stock_choices(OfxImageEffectHandle instance) {
    each_stock_row([&](const Parameter& row) {
        const std::string saved = Reader(instance, 0).get_string(id_param(row));
        if (saved.empty())
            record_choice(instance, row);  // a new node, or one saved before the ids were
        else
            set_choice_to(instance, row, saved);  // (an unknown stock stays, for read_parameters to report)
    });
}

void parameter_changed(OfxImageEffectHandle instance, const std::string& param, const std::string& reason,
                       OfxTime time) {
    if (param == kLoadLook) return load_look(instance, time);
    if (param == kSaveLook) return save_look(instance, time);
    each_stock_row([&](const Parameter& row) {
        if (param == row.ofx_name && reason == kOfxChangeUserEdited) record_choice(instance, row);
        // A host that sets the saved id after creating the node (or a script that sets it).
        if (param == id_param(row) && reason != kOfxChangePluginEdited)
            set_choice_to(instance, row, Reader(instance, 0).get_string(id_param(row)));
    });
}

}  // namespace darkroom::ofx
