#include "look/render.h"

#include <cmath>
#include <iostream>
#include <stdexcept>

#include "look/user_error.h"

namespace darkroom {

namespace {

Stock find_named_stock(const std::string& id_or_path, const Parameter& p, const Naming& name) {
    try {
        return find_stock(id_or_path);
    } catch (const StockError& e) {
        throw UserError(name(p) + ": " + e.what());
    }
}

std::shared_ptr<const GrainSynthesisPlan> plate_grain_of(const Look& look, const Naming& name, bool verbose) {
    if (look.grain_profile.empty()) return nullptr;
    GrainSynthesisPlan plan;
    try {
        plan = read_plate_grain(look.grain_profile,
                                GrainControls{look.grain_profile_gain, look.grain_profile_size, look.grain_profile_tilt});
    } catch (const UserError& e) {
        throw UserError(name(parameter("grain-profile")) + ": " + e.what());
    }
    // The grain is added to the output: its encoding must be the profile's (scan output is
    // Cineon log, the others scene-linear unless the output colour space says otherwise).
    const GrainProfile& profile = plan.profile;
    const std::string& output_space = look.colour.output_space;
    const SignalEncoding by_mode =
        look.settings.output == OutputMode::scan ? SignalEncoding::log : SignalEncoding::linear;
    const SignalEncoding output = encoding_of_colorspace(output_space, by_mode);
    if (output != profile.encoding)
        throw UserError(name(parameter("grain-profile")) + ": '" + look.grain_profile + "' was measured in " +
                        encoding_name(profile.encoding) + (profile.colorspace.empty() ? "" : " (" + profile.colorspace + ")") +
                        ", the output is " + encoding_name(output) + " (" +
                        (output_space.empty() ? "the " + parameter("output").get(look).get<std::string>() + " output"
                                              : output_space) +
                        "): set " + name(parameter("tocolorspace")) + " to the plate's colour space");
    if (!profile.colorspace.empty() && !output_space.empty() && profile.colorspace != output_space)
        std::cerr << "darkroom: warning: the grain profile was measured in '" << profile.colorspace
                  << "' but the output is in '" << output_space << "'\n";
    if (verbose)
        std::cerr << "grain: plate profile " << look.grain_profile << " (" << encoding_name(profile.encoding)
                  << (profile.colorspace.empty() ? "" : ", " + profile.colorspace) << ") replaces the stock's grain\n";
    return std::make_shared<const GrainSynthesisPlan>(std::move(plan));
}

void apply_plate_grain(const GrainSynthesisPlan& grain, const std::string& profile_path, const ImageView& image,
                       uint64_t seed, int frame, int threads) {
    try {
        apply_grain_profile(grain, image, seed, frame, threads);
    } catch (const std::invalid_argument& e) {
        throw UserError("'" + profile_path + "': " + e.what());
    }
}

// The settings the plan compiles with: the plate's grain replaces the stock's.
DevelopSettings plan_settings(const Look& look) {
    DevelopSettings settings = look.settings;
    settings.grain = settings.grain && look.grain_profile.empty();  // the plate's grain replaces the stock's
    return settings;
}

template <typename View, typename F>
void each_pixel(const View& image, const Window& window, F&& f) {
    for (int y = window.y0; y < window.y1; ++y)
        for (int x = window.x0; x < window.x1; ++x) f(image.at(x, y), x, y);
}

}  // namespace

Stock find_film(const Look& look, const Naming& name) { return find_named_stock(look.film, parameter("film"), name); }

std::optional<Stock> find_paper(const Look& look, const Naming& name) {
    if (look.paper == "none" || look.settings.output != OutputMode::print) return std::nullopt;
    return find_named_stock(look.paper, parameter("paper"), name);
}

FrameGeometry frame_geometry(const ConstImageView& in, int film_width_px, int film_height_px) {
    return FrameGeometry{in.window.width(), in.window.height(), colour_channel_count(in) == 1,
                         in.window.x0,      in.window.y0,       film_width_px,
                         film_height_px};
}

GrainSynthesisPlan read_plate_grain(const std::string& profile_path, const GrainControls& controls) {
    try {
        return plan_grain_synthesis(load_grain_profile_file(profile_path), controls);
    } catch (const GrainProfileError& e) {
        throw UserError(e.what());
    }
}


Renderer::Renderer(Look look, const Naming& name, bool verbose)
    : look_((validate(look, name), std::move(look))),
      name_(name),
      verbose_(verbose),
      colour_(look_.colour, look_.settings.output, verbose, name),
      plate_grain_(plate_grain_of(look_, name, verbose)) {}

Plan Renderer::compile(const FrameGeometry& frame, int threads) const {
    const Stock film = find_film(look_, name_);
    const std::optional<Stock> paper = find_paper(look_, name_);
    return compile(frame, threads, film, paper ? &*paper : nullptr);
}

Plan Renderer::compile(const FrameGeometry& frame, int threads, const Stock& film, const Stock* paper) const {
    try {
        Plan plan = Plan::compile(film, paper, plan_settings(look_), frame, threads);
        if (verbose_)
            for (const std::string& line : plan.describe()) std::cerr << line << "\n";
        return plan;
    } catch (const std::invalid_argument& e) {
        throw UserError(e.what());
    }
}

void Renderer::to_working(const ImageView& image, int premultiplied_alpha, int threads) const {
    const int colour_channels = colour_channel_count(image);
    if (premultiplied_alpha >= colour_channels && premultiplied_alpha < image.channels)
        each_pixel(image, image.window,
                   [&](float* px, int, int) { unpremultiply(px, colour_channels, px[premultiplied_alpha]); });
    colour_.input_to_working(image, threads);
}

ConstImageView Renderer::working_input(const Plan& plan, const ConstImageView& in, const Window& out_window,
                                       int premultiplied_alpha, Image& buffer, int threads) const {
    const int colour_channels = colour_channel_count(in);
    const bool premultiplied = premultiplied_alpha >= colour_channels && premultiplied_alpha < in.channels;
    if (colour_.input_conversion().is_noop() && !premultiplied) return in;
    // Per-pixel work on just the pixels the plan reads: a window stays that window of the
    // full render.
    const Window needed = plan.input_window(out_window);
    buffer = Image(needed, in.channels);
    ImageView working = buffer.view();
    working.colour_channels = in.colour_channels;
    each_pixel(working, needed, [&](float* px, int x, int y) { std::copy_n(in.at(x, y), in.channels, px); });
    to_working(working, premultiplied_alpha, threads);
    return working;
}

void Renderer::render(const Plan& plan, const ConstImageView& working, const ImageView& out, int frame,
                      int premultiplied_alpha, int threads) const {
    const int colour_channels = colour_channel_count(working);
    const bool premultiplied = premultiplied_alpha >= colour_channels && premultiplied_alpha < working.channels;
    plan.run(working, out, threads);
    ImageView colour = out;
    colour.colour_channels = 3;
    colour_.result_to_output(colour, threads);
    if (plate_grain_)
        apply_plate_grain(*plate_grain_, look_.grain_profile, colour, look_.settings.seed, frame, threads);
    each_pixel(out, out.window, [&](float* px, int x, int y) {
        const float* source = working.at(x, y);
        for (int c = 3; c < out.channels; ++c) px[c] = source[colour_channels + c - 3];
        if (premultiplied) premultiply(px, 3, source[premultiplied_alpha]);
    });
}

Image Renderer::develop(const Plan& plan, const ConstImageView& in, const Window& out_window, int frame,
                        int premultiplied_alpha, int threads) const {
    // RGB, then what the input has past its colour: alpha (grey and alpha input: RGBA) and
    // any further channels.
    Image out(out_window, 3 + in.channels - colour_channel_count(in));
    Image buffer;
    const ConstImageView working = working_input(plan, in, out_window, premultiplied_alpha, buffer, threads);
    render(plan, working, out.view(), frame, premultiplied_alpha, threads);
    return out;
}

void apply_plate_grain_to_element(const GrainSynthesisPlan& grain, const std::string& profile_path,
                                  const ImageView& image, int premultiplied_alpha, uint64_t seed, int frame,
                                  int threads) {
    const int colours = colour_channel_count(image);
    const bool premultiplied = premultiplied_alpha >= colours && premultiplied_alpha < image.channels;
    if (premultiplied)
        each_pixel(image, image.window, [&](float* px, int, int) { unpremultiply(px, colours, px[premultiplied_alpha]); });
    apply_plate_grain(grain, profile_path, image, seed, frame, threads);
    if (premultiplied)
        each_pixel(image, image.window, [&](float* px, int, int) { premultiply(px, colours, px[premultiplied_alpha]); });
}

std::vector<std::string> non_finite_warnings(const Plan& plan, const ConstImageView& in, const Window& out_window,
                                             int premultiplied_alpha) {
    const int colour_channels = colour_channel_count(in);
    const Window read = plan.input_window(out_window).intersected(in.window);
    size_t colour = 0, alpha = 0;
    each_pixel(in, read, [&](const float* px, int, int) {
        for (int c = 0; c < colour_channels; ++c) colour += !std::isfinite(px[c]);
        if (premultiplied_alpha >= 0) alpha += !std::isfinite(px[premultiplied_alpha]);
    });
    std::vector<std::string> warnings;
    if (colour > 0)
        warnings.push_back(std::to_string(colour) +
                           " non-finite colour values (NaN and -Inf count as no light, +Inf as 1e30)");
    if (alpha > 0)
        warnings.push_back(std::to_string(alpha) +
                           " non-finite alpha values (as coverage: NaN and -Inf count as 0, +Inf as 1)");
    return warnings;
}

Plan PlanCache::plan_for(const FrameGeometry& frame, int frame_number) {
    // Held while compiling: the other frames of this size need the same plan.
    std::lock_guard<std::mutex> lock(mutex_);
    // The film frame's size (its width sets the pitch, its height with it the preview's proxy
    // factor) and grey input need their own compile; each image's window of that frame (its
    // data window) is a copy of it.
    const auto key = std::make_tuple(frame.film_width_px(), frame.film_height_px(), frame.monochrome);
    auto it = plans_.find(key);
    if (it == plans_.end()) it = plans_.emplace(key, renderer_.compile(frame, threads_)).first;
    return it->second.in_image(frame).for_frame(frame_number);
}

}  // namespace darkroom
