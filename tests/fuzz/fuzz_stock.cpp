// Stock files (core/stock.h): darkroom-stock versions 1 and 2 and spektrafilm profiles, all
// through parse_stock_json. Rejection is a StockError; an accepted stock must be usable by
// the model: one or three layers, curves that are monotone functions, finite spectra with
// sensitivities and dyes of peak 1, a positive speed; stock_to_json must write it so
// that it reads back; and it must develop a frame to finite colour (fuzz_render.h) at the
// fast tier, as the film (its negative, and printed on the default paper) or as the paper
// (of the default film), or be refused with a UserError.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/stock.h"
#include "tests/fuzz/fuzz_check.h"
#include "tests/fuzz/fuzz_render.h"

namespace {

using namespace darkroom;

bool is_function(const Curve& c) {
    if (c.x.size() < 2 || c.x.size() != c.y.size()) return false;
    for (size_t i = 0; i < c.x.size(); ++i) {
        if (!std::isfinite(c.x[i]) || !std::isfinite(c.y[i])) return false;
        if (i > 0 && !(c.x[i] > c.x[i - 1])) return false;
    }
    return true;
}

// Density never falls with exposure, or for a reversal film never rises.
bool is_monotone(const Curve& c, StockKind kind) {
    const double sign = density_falls_with_exposure(kind) ? -1.0 : 1.0;
    for (size_t i = 1; i < c.y.size(); ++i)
        if (sign * (c.y[i] - c.y[i - 1]) < -1e-9) return false;  // (the reader's rounding tolerance)
    return true;
}

bool is_finite(const Spectrum& s) {
    return std::all_of(s.begin(), s.end(), [](double v) { return std::isfinite(v); });
}

bool has_peak_one(const Spectrum& s) {
    return is_finite(s) && *std::max_element(s.begin(), s.end()) == 1.0 &&
           *std::min_element(s.begin(), s.end()) >= 0.0;
}

void check_usable(const Stock& stock) {
    fuzz_require(stock.layers.size() == 1 || stock.layers.size() == 3);
    fuzz_require(std::isfinite(stock.iso_speed) && stock.iso_speed > 0);
    fuzz_require(std::isfinite(speed_point_log_h(stock)));
    fuzz_require(is_finite(stock.base_density) && is_finite(stock.exposure_illuminant));
    for (const Layer& layer : stock.layers) {
        fuzz_require(is_function(layer.density_curve) && is_monotone(layer.density_curve, stock.kind));
        fuzz_require(is_function(layer.mtf));
        fuzz_require(has_peak_one(layer.sensitivity));
        fuzz_require(has_peak_one(layer.dye_density));
        fuzz_require(std::isfinite(layer.grain.rms_granularity) && std::isfinite(layer.grain.grain_size_um) &&
                     std::isfinite(layer.grain.density_exponent));
        fuzz_require(std::isfinite(layer.halation.strength) && std::isfinite(layer.halation.radius_um));
    }
}

}  // namespace

namespace darkroom::fuzz {

// The stock in a render: a camera film's negative and its print on the default paper, or a
// paper's or print film's print of the default film. Each may be refused (a UserError).
void develops_finite_as_film_or_paper(const Stock& stock) {
    auto finite_or_refused = [](const Look& look, const Stock& film, const Stock* paper) {
        try {
            fuzz_require(develops_finite(look, Quality::fast, &film, paper).value_or(true));
        } catch (const UserError&) {
        }
    };
    const Look print;
    if (is_camera_film(stock.kind)) {
        Look negative;
        negative.paper = "none";
        negative.settings.output = OutputMode::negative;
        finite_or_refused(negative, stock, nullptr);
        const std::optional<Stock> paper = find_paper(print, flag_name);
        finite_or_refused(print, stock, paper ? &*paper : nullptr);
    } else {
        finite_or_refused(print, find_film(print, flag_name), &stock);
    }
}

}  // namespace darkroom::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    Stock stock;
    try {
        stock = parse_stock_json(text, "fuzz input");
    } catch (const StockError&) {
        return 0;
    }
    check_usable(stock);
    const Stock written = parse_stock_json(stock_to_json(stock), "the fuzz input's stock, written");
    fuzz_require(written.layers.size() == stock.layers.size());
    fuzz::develops_finite_as_film_or_paper(stock);
    return 0;
}
