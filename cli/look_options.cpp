#include "cli/look_options.h"

#include <cmath>
#include <iostream>
#include <stdexcept>

#include "cli/user_error.h"

namespace darkroom::cli {

namespace {

// A per-channel (R, G, B) setting given as one value for all channels or three.
// `default_text` is "" where the default is the stock's own value.
void add_per_channel_option(CLI::App& cmd, const std::string& name, std::array<double, 3>& values,
                            const std::string& what, double min, double max, const std::string& default_text) {
    cmd.add_option_function<std::vector<double>>(
           name,
           [&values, name](const std::vector<double>& v) {
               if (v.size() != 1 && v.size() != 3)
                   throw CLI::ValidationError(name, "give one value for all channels or three (R,G,B)");
               for (int c = 0; c < 3; ++c) values[c] = v[v.size() == 1 ? 0 : c];
           },
           what + " (one value, or R,G,B)")
        ->delimiter(',')
        ->expected(1, 3)
        ->check(CLI::Range(min, max))
        ->default_str(default_text);
}

}  // namespace

void add_look_flags(CLI::App& cmd, LookOptions& look) {
    DevelopSettings& s = look.settings;
    cmd.add_option("--film", look.film, "Film stock: a built-in id (see 'darkroom stocks') or a .json file")
        ->capture_default_str();
    cmd.add_option("--paper", look.paper, "Paper stock id or .json file, or 'none' to stop at the negative")
        ->capture_default_str();
    cmd.add_option("--exposure", s.exposure_ev, "Camera exposure in stops relative to the stock's ISO speed")
        ->capture_default_str();
    cmd.add_option("--print-exposure", s.print_exposure_ev, "Print exposure in stops relative to the automatic one")
        ->capture_default_str();
    add_choice(cmd, "--output", s.output,
               {{"print", OutputMode::print},
                {"negative", OutputMode::negative},
                {"density", OutputMode::density},
                {"scan", OutputMode::scan},
                {"texture", OutputMode::texture}},
               "What to write: print (colour of the print), negative (transmittance), density (per layer), "
               "scan (Cineon log code values), texture (the input with grain, MTF and halation only)");
    add_choice(cmd, "--quality", s.quality,
               {{"reference", Quality::reference}, {"high", Quality::high}, {"fast", Quality::fast},
                {"preview", Quality::preview}},
               "How each stage is computed: reference (from its definition; slow), high, fast or preview "
               "(README, Quality tiers; 'darkroom bench' measures each against the reference)");
    add_choice(cmd, "--input-units", s.input_units,
               {{"scene-linear", InputUnits::scene_linear}, {"lux-seconds", InputUnits::lux_seconds}},
               "scene-linear (metered so 0.18 is mid grey) or lux-seconds (pixels are the exposure H)");
    cmd.add_option("--seed", s.seed, "Grain seed")->capture_default_str();
    // The frame number belongs to the image, not the look.
    cmd.add_option("--frame", s.frame, "Frame number (each frame has its own grain)")
        ->capture_default_str()
        ->configurable(false);
    add_switch(cmd, "grain", s.grain, "Granularity (--no-grain leaves it out)");
    add_switch(cmd, "mtf", s.mtf, "Internal scattering, the MTF (--no-mtf leaves it out)");
    cmd.add_option("--grain-profile", look.grain_profile,
                   "A plate's grain profile (darkroom grain analyze/predict): replaces the stock's grain, added "
                   "to the result in the output colour space (which should be the plate's)")
        ->capture_default_str();
    cmd.add_option("--halation", s.halation, "Halation: multiplies the stock's per-layer strength (0 = off)")
        ->check(CLI::Range(0.0, 100.0))
        ->capture_default_str();
    add_per_channel_option(cmd, "--grain-amount", s.grain_amount, "Multiplies the stock's RMS granularity", 0.0, 100.0, "1");
    add_per_channel_option(cmd, "--grain-size", s.grain_size, "Multiplies the stock's grain size", 0.0, 100.0, "1");
    add_per_channel_option(cmd, "--grain-response", s.grain_density_exponent,
                           "Replaces the exponent of the grain's growth with net density, D^x (default: the stock's)",
                           0.0, 4.0, "");
    cmd.add_option("--printer-lights", s.printer_lights,
                   "Printer lights R,G,B in points: 25 = automatic (mid grey prints neutral); +1 point = +0.025 "
                   "log exposure of that paper layer (more red light: more cyan dye)")
        ->delimiter(',')
        ->default_str("[25,25,25]");
    cmd.add_option("--filtration", s.filtration_ymc, "Enlarger filtration Y,M,C in CC units, on top of the lights")
        ->delimiter(',')
        ->check(CLI::Range(0.0, 1000.0))
        ->default_str("[0,0,0]");
    cmd.add_option("--frame-width-mm", s.frame_width_mm, "Film frame width in mm (0: the stock's format)")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 1e4));
    cmd.add_option("--print-width-mm", s.print_width_mm, "Print width in mm (0: the paper's format)")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 1e4));
    // How to run, not how the image looks: kept out of look files.
    cmd.add_option("--threads", look.threads, "Worker threads (0 = all cores; default $OPENIMAGEIO_THREADS or 0)")
        ->check(CLI::Range(0, 1024))
        ->envname("OPENIMAGEIO_THREADS")
        ->configurable(false);
    cmd.add_flag("-v,--verbose", look.verbose,
                 "Print the plan (the stages run and those skipped) and the colour management")
        ->configurable(false);
    add_colour_flags(cmd, look.colour);
}

CLI::Option* add_switch(CLI::App& cmd, const std::string& name, bool& value, const std::string& help) {
    return cmd.add_flag("--" + name + ",!--no-" + name, value, help)->default_str(value ? "true" : "false");
}

Plan compile_look(const LookOptions& look, const FrameGeometry& frame) {
    try {
        Stock film = find_stock(look.film);
        bool no_paper = look.paper == "none" || look.settings.output != OutputMode::print;
        Stock paper = no_paper ? Stock{} : find_stock(look.paper);
        if (look.paper == "none" && look.settings.output == OutputMode::print)
            throw UserError("--paper none stops at the negative: use --output negative or density");
        DevelopSettings settings = look.settings;
        settings.grain = settings.grain && look.grain_profile.empty();  // the plate's grain replaces the stock's
        Plan plan = Plan::compile(film, no_paper ? nullptr : &paper, settings, frame, look.threads);
        if (look.verbose)
            for (const std::string& line : plan.describe()) std::cerr << line << "\n";
        return plan;
    } catch (const StockError& e) {
        throw UserError(e.what());
    } catch (const std::invalid_argument& e) {
        throw UserError(e.what());
    }
}

GrainSynthesisPlan read_plate_grain(const std::string& profile_path) {
    try {
        return plan_grain_synthesis(load_grain_profile_file(profile_path));
    } catch (const GrainProfileError& e) {
        throw UserError(e.what());
    }
}

void load_plate_grain(LookOptions& look) {
    if (look.grain_profile.empty()) return;
    look.plate_grain = std::make_shared<const GrainSynthesisPlan>(read_plate_grain(look.grain_profile));
    const GrainProfile& profile = look.plate_grain->profile;
    const std::string& output_space = look.colour.output_space;
    if (!profile.colorspace.empty() && !output_space.empty() && profile.colorspace != output_space)
        std::cerr << "darkroom: warning: the grain profile was measured in '" << profile.colorspace
                  << "' but the output is in '" << output_space << "'\n";
    if (look.verbose)
        std::cerr << "grain: plate profile " << look.grain_profile << " (" << encoding_name(profile.encoding)
                  << (profile.colorspace.empty() ? "" : ", " + profile.colorspace) << ") replaces the stock's grain\n";
}

void apply_plate_grain(const GrainSynthesisPlan& grain, const std::string& profile_path, const ImageView& image,
                       uint64_t seed, int frame, int threads) {
    try {
        apply_grain_profile(grain, image, seed, frame, threads);
    } catch (const std::invalid_argument& e) {
        throw UserError("'" + profile_path + "': " + e.what());
    }
}

void apply_plate_grain_to_element(const GrainSynthesisPlan& grain, const std::string& profile_path,
                                  const ImageView& image, int premultiplied_alpha, uint64_t seed, int frame,
                                  int threads) {
    const int colours = colour_channel_count(image);
    const bool premultiplied = premultiplied_alpha >= colours && premultiplied_alpha < image.channels;
    auto each_pixel = [&](auto&& f) {
        for (int y = image.window.y0; y < image.window.y1; ++y)
            for (int x = image.window.x0; x < image.window.x1; ++x) f(image.at(x, y));
    };
    if (premultiplied) each_pixel([&](float* px) { unpremultiply(px, colours, px[premultiplied_alpha]); });
    apply_plate_grain(grain, profile_path, image, seed, frame, threads);
    if (premultiplied) each_pixel([&](float* px) { premultiply(px, colours, px[premultiplied_alpha]); });
}

FrameGeometry frame_geometry(const ConstImageView& in, int film_width_px) {
    return FrameGeometry{in.window.width(), in.window.height(), colour_channel_count(in) == 1, in.window.x0, in.window.y0, film_width_px};
}

Plan PlanCache::plan_for(const FrameGeometry& frame, int frame_number) {
    // Held while compiling: the other frames of this size need the same plan.
    std::lock_guard<std::mutex> lock(mutex_);
    // The film frame's width and grey input need their own compile; each image's window of
    // that frame (its data window) is a copy of it.
    const auto key = std::make_pair(frame.film_width_px(), frame.monochrome);
    auto it = plans_.find(key);
    if (it == plans_.end()) it = plans_.emplace(key, compile_look(look_, frame)).first;
    return it->second.in_image(frame).for_frame(frame_number);
}

std::vector<std::string> non_finite_warnings(const Plan& plan, const ConstImageView& in, const Window& out_window,
                                             int premultiplied_alpha) {
    const int colour_channels = colour_channel_count(in);
    const Window read = plan.input_window(out_window).intersected(in.window);
    size_t colour = 0, alpha = 0;
    for (int y = read.y0; y < read.y1; ++y)
        for (int x = read.x0; x < read.x1; ++x) {
            const float* px = in.at(x, y);
            for (int c = 0; c < colour_channels; ++c) colour += !std::isfinite(px[c]);
            if (premultiplied_alpha >= 0) alpha += !std::isfinite(px[premultiplied_alpha]);
        }
    std::vector<std::string> warnings;
    if (colour > 0)
        warnings.push_back(std::to_string(colour) +
                           " non-finite colour values (NaN and -Inf count as no light, +Inf as 1e30)");
    if (alpha > 0)
        warnings.push_back(std::to_string(alpha) +
                           " non-finite alpha values (as coverage: NaN and -Inf count as 0, +Inf as 1)");
    return warnings;
}

Image develop_image(const LookOptions& look, const ColourIO& colour, const Plan& plan, const ConstImageView& in,
                    const Window& out_window, int premultiplied_alpha) {
    // RGB, then what the input has past its colour: alpha (grey and alpha input: RGBA) and
    // any further channels.
    const int colour_channels = colour_channel_count(in);
    const bool premultiplied = premultiplied_alpha >= colour_channels && premultiplied_alpha < in.channels;
    Image out(out_window, 3 + in.channels - colour_channels);
    if (colour.input_conversion().is_noop() && !premultiplied) {
        plan.run(in, out.view(), look.threads);
    } else {
        // Per-pixel work on just the pixels the plan reads: a window stays that window of the
        // full render.
        const Window needed = plan.input_window(out_window);
        Image working(needed, in.channels);
        ImageView working_view = working.view();
        working_view.colour_channels = in.colour_channels;
        for (int y = needed.y0; y < needed.y1; ++y)
            for (int x = needed.x0; x < needed.x1; ++x) {
                float* px = working.at(x, y);
                std::copy_n(in.at(x, y), in.channels, px);
                if (premultiplied) unpremultiply(px, colour_channels, px[premultiplied_alpha]);
            }
        colour.input_to_working(working_view, look.threads);
        plan.run(working_view, out.view(), look.threads);
    }
    colour.result_to_output(out, look.threads);
    // The plate's grain on the result, keyed like the film grain (seed, frame, absolute pixel).
    if (!look.grain_profile.empty() && !look.plate_grain)
        throw std::logic_error("the grain profile '" + look.grain_profile + "' was not read (load_plate_grain)");
    if (look.plate_grain)
        apply_plate_grain(*look.plate_grain, look.grain_profile, out.view(), look.settings.seed, look.settings.frame,
                          look.threads);
    for (int y = out.window.y0; y < out.window.y1; ++y)
        for (int x = out.window.x0; x < out.window.x1; ++x) {
            float* px = out.at(x, y);
            for (int c = 3; c < out.channels; ++c) px[c] = in.at(x, y)[colour_channels + c - 3];
            if (premultiplied) premultiply(px, 3, in.at(x, y)[premultiplied_alpha]);
        }
    return out;
}

}  // namespace darkroom::cli
