// Shared fixtures for core tests: a small stock defined in the test itself.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "core/develop.h"
#include "core/simd.h"
#include "core/stock.h"

namespace darkroom::test {

// A one-layer panchromatic film with a parametric curve, a Gaussian-like MTF and grain.
inline std::string test_film_json(const std::string& grain = R"({"rms_granularity": 0.012, "grain_size_um": 1.5})") {
    return R"({
      "format": "darkroom-stock", "version": 1, "id": "test-film", "name": "Test film", "kind": "negative",
      "iso_speed": 200, "frame_width_mm": 36,
      "layers": [{
        "name": "silver",
        "spectral_sensitivity": {"emulsion": "panchromatic"},
        "density_curve": {"parametric": {"gamma": 0.65, "d_min": 0.25, "d_max": 2.6, "toe": 0.12, "shoulder": 0.2}},
        "mtf": {"cycles_per_mm": [0, 10, 20, 40, 60, 80, 120], "response": [1.0, 0.97, 0.9, 0.7, 0.5, 0.35, 0.17]},
        "grain": )" + grain + R"(
      }]})";
}

inline std::string test_paper_json() {
    return R"({
      "format": "darkroom-stock", "version": 1, "id": "test-paper", "name": "Test paper", "kind": "paper",
      "iso_speed": 250, "frame_width_mm": 254,
      "layers": [{
        "name": "silver",
        "spectral_sensitivity": {"emulsion": "blue-sensitive"},
        "density_curve": {"parametric": {"gamma": 1.67, "d_min": 0.05, "d_max": 2.1, "toe": 0.1, "shoulder": 0.15}},
        "mtf": {"cycles_per_mm": [0, 5, 10, 20], "response": [1.0, 0.9, 0.7, 0.4]},
        "grain": {"rms_granularity": 0.002, "grain_size_um": 1.0}
      }]})";
}

// A three-layer colour negative and a colour paper in format version 2, with Gaussian
// sensitivities and dyes, an orange mask, halation and grain: shapes like real stocks',
// numbers chosen for the tests (not any maker's).
inline std::string test_colour_film_json() {
    auto layer = [](const char* name, int nm, double d_min, const char* dye, double halation) {
        return std::string(R"({"name": ")") + name + R"(",
          "spectral_sensitivity": {"gaussians": [{"nm": )" + std::to_string(nm) + R"(, "sigma_nm": 28, "weight": 1}]},
          "density_curve": {"softplus": {"d_min": )" + std::to_string(d_min) + R"(, "knots": [
              {"log_h": -2.6, "slope": 0.6, "width": 0.2}, {"log_h": 1.0, "slope": -0.6, "width": 0.4}]}},
          "dye_density": )" + dye + R"(,
          "mtf": {"cycles_per_mm": [0, 20, 40, 80], "response": [1.0, 0.9, 0.7, 0.35]},
          "grain": {"rms_granularity": 0.008, "grain_size_um": 1.5, "density_exponent": 0.5},
          "halation": {"strength": )" + std::to_string(halation) + R"(, "radius_um": 60}})";
    };
    return R"({"format": "darkroom-stock", "version": 2, "id": "test-colour-film", "name": "Test colour film",
      "kind": "negative", "iso_speed": 250, "frame_width_mm": 24.89, "exposure_illuminant": "D55",
      "base_density": {"constant": 0.1, "gaussians": [{"nm": 440, "sigma_nm": 40, "weight": 0.7},
                                                      {"nm": 520, "sigma_nm": 30, "weight": 0.4}]},
      "layers": [)" +
           layer("red", 650, 0.2, R"({"gaussians": [{"nm": 680, "sigma_nm": 55, "weight": 1}, {"nm": 440, "sigma_nm": 40, "weight": 0.1}]})", 0.04) + "," +
           layer("green", 545, 0.6, R"({"gaussians": [{"nm": 550, "sigma_nm": 40, "weight": 1}, {"nm": 440, "sigma_nm": 30, "weight": 0.15}]})", 0.012) + "," +
           layer("blue", 450, 0.8, R"({"gaussians": [{"nm": 450, "sigma_nm": 35, "weight": 1}]})", 0.004) + "]}";
}

inline std::string test_colour_paper_json() {
    auto layer = [](const char* name, int nm, const char* dye) {
        return std::string(R"({"name": ")") + name + R"(",
          "spectral_sensitivity": {"gaussians": [{"nm": )" + std::to_string(nm) + R"(, "sigma_nm": 18, "weight": 1}]},
          "density_curve": {"softplus": {"d_min": 0.08, "knots": [
              {"log_h": 0.0, "slope": 2.2, "width": 0.12}, {"log_h": 1.0, "slope": -2.2, "width": 0.12}]}},
          "dye_density": )" + dye + R"(,
          "mtf": {"cycles_per_mm": [0, 5, 10, 20], "response": [1.0, 0.9, 0.7, 0.4]},
          "grain": {"rms_granularity": 0.0, "grain_size_um": 1.0}})";
    };
    return R"({"format": "darkroom-stock", "version": 2, "id": "test-colour-paper", "name": "Test colour paper",
      "kind": "paper", "iso_speed": 100, "frame_width_mm": 254, "exposure_illuminant": "3200K",
      "mid_grey_aim_density": 0.7447,
      "layers": [)" +
           layer("red", 690, R"({"gaussians": [{"nm": 660, "sigma_nm": 45, "weight": 1}]})") + "," +
           layer("green", 545, R"({"gaussians": [{"nm": 545, "sigma_nm": 38, "weight": 1}]})") + "," +
           layer("blue", 460, R"({"gaussians": [{"nm": 445, "sigma_nm": 30, "weight": 1}]})") + "]}";
}

inline Stock test_film() { return parse_stock_json(test_film_json(), "test film"); }
inline Stock test_colour_film() { return parse_stock_json(test_colour_film_json(), "test colour film"); }
inline Stock test_colour_paper() { return parse_stock_json(test_colour_paper_json(), "test colour paper"); }
inline Stock test_paper() { return parse_stock_json(test_paper_json(), "test paper"); }

// The message of the StockError that parsing `json` (named `origin`) throws, or "no error".
inline std::string stock_error_of(const std::string& json, const std::string& origin) {
    try {
        parse_stock_json(json, origin);
    } catch (const StockError& e) {
        return e.what();
    }
    return "no error";
}

// `text` with its one occurrence of `from` replaced by `to` (which must be there).
inline std::string replaced(std::string text, const std::string& from, const std::string& to) {
    size_t at = text.find(from);
    if (at == std::string::npos) throw std::logic_error("test fixture lacks: " + from);
    return text.replace(at, from.size(), to);
}

// Develops `in` (its window is the whole frame) and returns `window` of the result (default all).
inline Image render(const Stock& film, const Stock* paper, const DevelopSettings& s, const Image& in, int threads = 1,
                    Window window = {}) {
    Plan plan = Plan::compile(film, paper, s, {in.window.width(), in.window.height()});
    Image out(window.empty() ? in.window : window, 3);
    plan.run(in.view(), out.view(), threads);
    return out;
}

// The instruction sets this processor runs, narrowest first.
inline std::vector<simd::Isa> runnable_isas() {
    std::vector<simd::Isa> isas;
    for (simd::Isa isa : {simd::Isa::baseline, simd::Isa::avx2, simd::Isa::avx512})
        if (int(isa) <= int(simd::widest_isa())) isas.push_back(isa);
    return isas;
}

// Restores the dispatch's choice when a test ends, however it ends.
struct IsaScope {
    simd::Isa saved = simd::isa();
    ~IsaScope() { simd::set_isa(saved); }
};

}  // namespace darkroom::test
