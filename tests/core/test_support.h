// Shared fixtures for core tests: a small stock defined in the test itself.
#pragma once

#include <string>

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

inline Stock test_film() { return parse_stock_json(test_film_json(), "test film"); }
inline Stock test_paper() { return parse_stock_json(test_paper_json(), "test paper"); }

}  // namespace darkroom::test
