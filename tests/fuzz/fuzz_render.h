// What the fuzz targets check of an accepted file past its parser: the README's promise that
// every accepted input gives finite colour. A tiny frame holding the whole range a pipeline
// hands in (black, the toe, mid grey, highlights, 1e30, and the bad pixels the program takes:
// NaN, +-Inf, negative) is rendered with the file's look, stock or grain profile, and every
// colour value that comes out must be finite. A refusal (UserError naming the setting) is an
// answer too; a render that gives NaN or Inf is the bug.
#pragma once

#include <cmath>
#include <limits>
#include <optional>

#include "look/render.h"
#include "look/user_error.h"

namespace darkroom::fuzz {

// 12x6 pixels, RGB: each row a pixel value from the list, in each channel or one channel at a
// time, so every value meets the others in a pixel.
inline Image test_frame() {
    constexpr float inf = std::numeric_limits<float>::infinity();
    const float values[12] = {0.0f, 1e-6f, 0.002f, 0.18f, 1.0f, 16.0f, 1e4f, 1e30f, inf, -inf, -1.0f,
                              std::numeric_limits<float>::quiet_NaN()};
    Image frame(12, 6, 3);
    for (int y = 0; y < 6; ++y)
        for (int x = 0; x < 12; ++x)
            for (int c = 0; c < 3; ++c)
                frame.at(x, y)[c] = y < 3 ? (c == y ? values[x] : 0.18f) : values[(x + 4 * c + y) % 12];
    return frame;
}

inline bool all_finite(const Image& image, int colour_channels) {
    for (size_t i = 0; i < image.pixels.size(); ++i)
        if (int(i % image.channels) < colour_channels && !std::isfinite(image.pixels[i])) return false;
    return true;
}

// The silver grains a reference render of the test frame may draw and stay cheap (about a
// second): its time grows with the film's area a pixel covers (Plan::silver_grains_per_pixel).
constexpr double kCheapReferenceGrains = 1e7;

// Develops the test frame with `look` (`film` and `paper` in place of the look's, where given)
// at `quality`; whether every colour value is finite, none where the reference tier would
// draw more than kCheapReferenceGrains. Throws UserError where the look, with the stocks, is
// refused.
inline std::optional<bool> develops_finite(Look look, Quality quality, const Stock* film = nullptr,
                                           const Stock* paper = nullptr) {
    look.settings.quality = quality;
    const Renderer renderer(look, flag_name);
    const Image frame = test_frame();
    const ConstImageView in = frame.view();
    const FrameGeometry geometry = frame_geometry(in);
    const int threads = 1;
    const Plan plan = (film ? renderer.compile(geometry, threads, *film, paper)
                            : renderer.compile(geometry, threads))
                          .for_frame(1001);
    if (plan.silver_grains_per_pixel() * double(in.window.pixel_count()) > kCheapReferenceGrains) return std::nullopt;
    return all_finite(renderer.develop(plan, in, in.window, 1001, -1, threads), 3);
}

// A plate's grain from `grain` on the test frame: finite wherever the frame is (the grain
// leaves non-finite pixels alone).
inline bool grains_finite(const GrainSynthesisPlan& grain) {
    const Image clean = test_frame();
    Image grained = clean;
    apply_plate_grain_to_element(grain, "the fuzz input", grained.view(), -1, 7, 1001, 1);
    for (size_t i = 0; i < clean.pixels.size(); ++i)
        if (std::isfinite(clean.pixels[i]) && !std::isfinite(grained.pixels[i])) return false;
    return true;
}

}  // namespace darkroom::fuzz
