// The darkroom Python module: develops numpy arrays with the same looks as the darkroom
// program and the plugin. Keyword arguments are the parameter table's Python keywords
// (look/parameters.h: exposure=0.5, print_exposure=-1, grain=False, film="kodak-t-max-100"),
// checked by the table's one check, and they override the look file as flags do.
#include <optional>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "core/plane_memory.h"
#include "look/render.h"
#include "look/user_error.h"

namespace py = pybind11;
using darkroom::Look;

namespace {

// A Python value as JSON, as the table's check takes it: None, bools, integers (a seed up
// to 2^64 - 1 exactly), floats, strings, and lists or tuples of them.
nlohmann::json json_of(const py::handle& value) {
    if (value.is_none()) return nullptr;
    if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
    if (py::isinstance<py::int_>(value)) {
        if (value.cast<py::int_>() < py::int_(0)) return value.cast<long long>();
        try {
            return value.cast<uint64_t>();
        } catch (const py::cast_error&) {
            return py::str(value).cast<std::string>();  // past 64 bits: refused as not a whole number in range
        }
    }
    if (py::isinstance<py::float_>(value)) return value.cast<double>();
    if (py::isinstance<py::str>(value)) return value.cast<std::string>();
    if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
        nlohmann::json array = nlohmann::json::array();
        for (const auto& element : value) array.push_back(json_of(element));
        return array;
    }
    return py::str(value).cast<std::string>();
}

// The look a look file and keywords give: the file's settings, the keywords over them.
Look look_of(const std::string& look_file, const py::kwargs& settings) {
    Look look = look_file.empty() ? Look{} : darkroom::read_look_file(look_file);
    for (const auto& [key, value] : settings) {
        const std::string keyword = py::str(key).cast<std::string>();
        const darkroom::Parameter* p = nullptr;
        for (const darkroom::Parameter& row : darkroom::parameters())
            if (row.python_keyword() == keyword) p = &row;
        if (!p) {
            std::string near = darkroom::closest_key(keyword);
            std::replace(near.begin(), near.end(), '-', '_');
            throw py::type_error("darkroom: unknown setting '" + keyword + "'" +
                                 (near.empty() ? "" : " (did you mean '" + near + "'?)"));
        }
        try {
            darkroom::set_value(look, *p, json_of(value));
        } catch (const darkroom::UserError& e) {
            throw darkroom::UserError(darkroom::python_name(*p) + " " + e.what());
        }
    }
    return look;
}

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

// An image array's height, width and channels; ValueError for any other shape or none.
struct ArrayShape {
    int height, width, channels;
};
ArrayShape array_shape(const FloatArray& pixels) {
    if (pixels.ndim() != 3 && pixels.ndim() != 2)
        throw py::value_error("darkroom: pixels must be an array of shape (height, width) or (height, width, channels)");
    const ArrayShape shape{int(pixels.shape(0)), int(pixels.shape(1)), pixels.ndim() == 3 ? int(pixels.shape(2)) : 1};
    if (shape.width <= 0 || shape.height <= 0 || shape.channels <= 0)
        throw py::value_error("darkroom: the image has no pixels");
    return shape;
}

py::array_t<float> develop(FloatArray pixels, const std::string& look_file, int frame, int threads, bool premultiplied,
                           const py::kwargs& settings) {
    const auto [height, width, channels] = array_shape(pixels);
    const darkroom::Renderer renderer(look_of(look_file, settings), darkroom::python_name);

    const darkroom::Window full{0, 0, width, height};
    const darkroom::ConstImageView in{pixels.data(), full, channels, channels, (std::ptrdiff_t)channels * width};
    std::optional<darkroom::Plan> plan;
    {
        py::gil_scoped_release release;
        plan = renderer.compile(darkroom::frame_geometry(in), threads).for_frame(frame);
    }
    // The alpha is the channel after the colour (RGBA, YA), as OpenImageIO names it.
    const int alpha = darkroom::colour_channel_count(channels);
    const int premultiplied_alpha = premultiplied && alpha < channels ? alpha : -1;
    // Before a render that will take hours (a filter set to "error" refuses it), and of
    // non-finite input, as the program warns; one over the reference tier's budget raises
    // ValueError.
    std::vector<std::string> warnings = darkroom::non_finite_warnings(*plan, in, full, premultiplied_alpha);
    warnings.push_back(darkroom::check_reference_render_budget(*plan, full, "quality="));
    for (const std::string& warning : warnings)
        if (!warning.empty() && PyErr_WarnEx(PyExc_RuntimeWarning, ("darkroom: " + warning).c_str(), 1) < 0)
            throw py::error_already_set();
    darkroom::Image out;
    {
        py::gil_scoped_release release;
        out = renderer.develop(*plan, in, full, frame, premultiplied_alpha, threads);
    }
    py::array_t<float> result({height, width, out.channels});
    std::copy(out.pixels.begin(), out.pixels.end(), result.mutable_data());
    return result;
}

py::object look_settings(const std::string& look_file, const py::kwargs& settings) {
    return py::module_::import("json").attr("loads")(look_of(look_file, settings).to_json().dump());
}

// A plate's grain on a clean element, as `darkroom grain apply` puts it: the same pixels.
py::array_t<float> grain_apply(FloatArray pixels, const std::string& profile_path, uint64_t seed, int frame,
                               int threads, bool premultiplied) {
    const auto [height, width, channels] = array_shape(pixels);
    const darkroom::GrainSynthesisPlan grain = darkroom::read_plate_grain(profile_path);
    py::array_t<float> result(pixels.request().shape);
    std::copy_n(pixels.data(), size_t(height) * width * channels, result.mutable_data());
    const darkroom::ImageView view{result.mutable_data(), {0, 0, width, height}, channels, channels,
                                   (std::ptrdiff_t)channels * width};
    // The alpha is the channel after the colour (RGBA, YA), as develop takes it.
    const int alpha = darkroom::colour_channel_count(channels);
    {
        py::gil_scoped_release release;
        darkroom::apply_plate_grain_to_element(grain, profile_path, view, premultiplied ? alpha : -1, seed, frame,
                                                    threads);
    }
    return result;
}

void save_look(const std::string& path, const std::string& look_file, const py::kwargs& settings) {
    darkroom::write_look_file(path, look_of(look_file, settings));
}

// The parameter table as Python sees it: each setting's keyword, type, unit, default and range.
py::list parameter_table() {
    py::list rows;
    const py::object loads = py::module_::import("json").attr("loads");
    for (const darkroom::Parameter& p : darkroom::parameters()) {
        nlohmann::json row = {{"keyword", p.python_keyword()}, {"key", p.key},
                              {"unit", p.unit},                {"group", p.group},
                              {"help", p.help},                {"default", p.default_value()},
                              {"animatable", p.animatable},    {"per_pixel", p.per_pixel},
                              {"label", p.label},              {"ofx_name", p.ofx_name}};
        if (p.type == darkroom::ParameterType::number || p.type == darkroom::ParameterType::per_channel)
            row["min"] = p.min, row["max"] = p.max;
        for (const darkroom::Choice& c : p.choices) row["choices"].push_back(c.name);
        rows.append(loads(row.dump()));
    }
    return rows;
}

}  // namespace

PYBIND11_MODULE(darkroom, m) {
    m.doc() = "Photographic film and paper development for numpy images (the darkroom program's engine)";
    py::register_exception<darkroom::UserError>(m, "DarkroomError", PyExc_ValueError);
    m.def("develop", &develop, py::arg("pixels"), py::kw_only(), py::arg("look") = "", py::arg("frame") = 0,
          py::arg("threads") = 0, py::arg("premultiplied") = true,
          "Develops a scene-linear float image of shape (height, width[, channels]); returns (height, width, "
          "max(3, channels)) float32. look: a look file; frame: the frame number (each frame has its own grain); "
          "premultiplied: the colour is premultiplied by the alpha after it (RGBA, YA), as OpenImageIO reads "
          "files: divided out before developing and multiplied back after (False: straight colour); "
          "other keywords: the look's settings (darkroom.parameters()), overriding the look file.");
    m.def("grain_apply", &grain_apply, py::arg("pixels"), py::arg("profile"), py::kw_only(), py::arg("seed") = 0,
          py::arg("frame") = 0, py::arg("threads") = 0, py::arg("premultiplied") = true,
          "A plate's grain (a profile from darkroom grain analyze or predict) on a clean float image of shape "
          "(height, width[, channels]) in the profile's encoding, as 'darkroom grain apply' puts it: returns a "
          "float32 array of the same shape. Grey by the channel count (one or two channels: grey, grey and alpha); "
          "premultiplied: the colour is premultiplied by the alpha after it, and gets grain on its light.");
    m.def("release_memory", &darkroom::release_plane_memory,
          "Frees the working planes develop keeps for the next image (up to 2 GB; about 0.3 GB after a 4K frame "
          "developed stage by stage: the high and reference tiers and the texture output); "
          "returns the bytes freed.");
    m.def("look", &look_settings, py::kw_only(), py::arg("look") = "",
          "The look (a dict, as a look file holds it) that these keywords and look file give.");
    m.def("parameters", &parameter_table,
          "The look's settings (the keywords develop, look and save_look take): a list of dicts with each one's "
          "keyword, look-file key, unit, group, help, default, range (min, max), choices, and the plugin's label "
          "and parameter name.");
    m.def(
        "look_schema", [] { return py::module_::import("json").attr("loads")(darkroom::look_schema().dump()); },
        "The JSON Schema of look files (a dict), made from the parameter table.");
    m.def("save_look", &save_look, py::arg("path"), py::kw_only(), py::arg("look") = "",
          "Writes the look these keywords and look file give to a look file.");
}
