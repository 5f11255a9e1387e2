// The darkroom Python module: develops numpy arrays with the same settings and look files as
// the darkroom program. Keyword arguments are the program's look flags with '_' for '-'
// (exposure=0.5, print_exposure=-1, grain=False, film="kodak-t-max-100"); they go through
// the same CLI11 flag definitions and look-file reader, so every flag the program knows is
// known here, with the same checks, and keywords override the look file as flags do.
#include <optional>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "cli/look_file.h"
#include "cli/look_options.h"
#include "cli/user_error.h"
#include "core/plane_memory.h"

namespace py = pybind11;
using darkroom::cli::LookOptions;

namespace {

// The look flags parsed from Python keywords, then the look file under them.
struct ParsedLook {
    CLI::App app{"darkroom"};
    LookOptions look;
    std::string look_path, save_look_path;

    ParsedLook(const std::string& look_file, const py::kwargs& settings) {
        darkroom::cli::add_look_file_flags(app, look_path, save_look_path);
        darkroom::cli::add_look_flags(app, look);
        std::vector<std::string> args;
        for (const auto& [key, value] : settings) {
            std::string flag = "--" + py::str(key).cast<std::string>();
            std::replace(flag.begin(), flag.end(), '_', '-');
            if (app.get_option_no_throw(flag) == nullptr)
                throw py::type_error("darkroom: unknown setting '" + py::str(key).cast<std::string>() +
                                     "' (the program's look flags, with '_' for '-')");
            if (py::isinstance<py::bool_>(value)) {
                args.push_back(flag + "=" + (value.cast<bool>() ? "true" : "false"));
            } else if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
                args.push_back(flag);
                for (const auto& element : value) args.push_back(py::str(element).cast<std::string>());
            } else {
                args.push_back(flag);
                args.push_back(py::str(value).cast<std::string>());
            }
        }
        std::reverse(args.begin(), args.end());  // CLI11 takes its arguments last first
        try {
            app.parse(args);
        } catch (const CLI::ParseError& e) {
            throw py::value_error(std::string("darkroom: ") + e.what());
        }
        if (!look_file.empty()) darkroom::cli::apply_look_file(app, look_file);
    }
};

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
    ParsedLook parsed(look_file, settings);
    parsed.look.settings.frame = frame;
    parsed.look.threads = threads;
    darkroom::cli::load_plate_grain(parsed.look);

    const darkroom::Window full{0, 0, width, height};
    const darkroom::ConstImageView in{pixels.data(), full, channels, channels, (std::ptrdiff_t)channels * width};
    std::optional<darkroom::Plan> plan;
    {
        py::gil_scoped_release release;
        plan = darkroom::cli::compile_look(parsed.look, darkroom::cli::frame_geometry(in));
    }
    // The alpha is the channel after the colour (RGBA, YA), as OpenImageIO names it.
    const int alpha = darkroom::colour_channel_count(channels);
    const int premultiplied_alpha = premultiplied && alpha < channels ? alpha : -1;
    // Before a render that will take hours (a filter set to "error" refuses it), and of
    // non-finite input, as the program warns.
    std::vector<std::string> warnings = darkroom::cli::non_finite_warnings(*plan, in, full, premultiplied_alpha);
    warnings.push_back(darkroom::long_reference_render_warning(*plan, full, "quality="));
    for (const std::string& warning : warnings)
        if (!warning.empty() && PyErr_WarnEx(PyExc_RuntimeWarning, ("darkroom: " + warning).c_str(), 1) < 0)
            throw py::error_already_set();
    const darkroom::cli::ColourIO colour(parsed.look.colour, parsed.look.settings.output, parsed.look.verbose);
    darkroom::Image out;
    {
        py::gil_scoped_release release;
        out = darkroom::cli::develop_image(parsed.look, colour, *plan, in, full, premultiplied_alpha);
    }
    py::array_t<float> result({height, width, out.channels});
    std::copy(out.pixels.begin(), out.pixels.end(), result.mutable_data());
    return result;
}

py::object look_settings(const std::string& look_file, const py::kwargs& settings) {
    ParsedLook parsed(look_file, settings);
    return py::module_::import("json").attr("loads")(darkroom::cli::look_json(parsed.app).dump());
}

// A plate's grain on a clean element, as `darkroom grain apply` puts it: the same pixels.
py::array_t<float> grain_apply(FloatArray pixels, const std::string& profile_path, uint64_t seed, int frame,
                               int threads, bool premultiplied) {
    const auto [height, width, channels] = array_shape(pixels);
    const darkroom::GrainSynthesisPlan grain = darkroom::cli::read_plate_grain(profile_path);
    py::array_t<float> result(pixels.request().shape);
    std::copy_n(pixels.data(), size_t(height) * width * channels, result.mutable_data());
    const darkroom::ImageView view{result.mutable_data(), {0, 0, width, height}, channels, channels,
                                   (std::ptrdiff_t)channels * width};
    // The alpha is the channel after the colour (RGBA, YA), as develop takes it.
    const int alpha = darkroom::colour_channel_count(channels);
    {
        py::gil_scoped_release release;
        darkroom::cli::apply_plate_grain_to_element(grain, profile_path, view, premultiplied ? alpha : -1, seed, frame,
                                                    threads);
    }
    return result;
}

void save_look(const std::string& path, const std::string& look_file, const py::kwargs& settings) {
    ParsedLook parsed(look_file, settings);
    darkroom::cli::save_look_file(parsed.app, path);
}

}  // namespace

PYBIND11_MODULE(darkroom, m) {
    m.doc() = "Photographic film and paper development for numpy images (the darkroom program's engine)";
    py::register_exception<darkroom::cli::UserError>(m, "DarkroomError", PyExc_ValueError);
    m.def("develop", &develop, py::arg("pixels"), py::kw_only(), py::arg("look") = "", py::arg("frame") = 0,
          py::arg("threads") = 0, py::arg("premultiplied") = true,
          "Develops a scene-linear float image of shape (height, width[, channels]); returns (height, width, "
          "max(3, channels)) float32. look: a look file; frame: the frame number (each frame has its own grain); "
          "premultiplied: the colour is premultiplied by the alpha after it (RGBA, YA), as OpenImageIO reads "
          "files: divided out before developing and multiplied back after (False: straight colour); "
          "other keywords: the program's look flags with '_' for '-', overriding the look file.");
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
    m.def("save_look", &save_look, py::arg("path"), py::kw_only(), py::arg("look") = "",
          "Writes the look these keywords and look file give to a look file.");
}
