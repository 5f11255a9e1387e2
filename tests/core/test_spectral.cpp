#include <catch2/catch.hpp>
#include <cmath>

#include "core/spectral.h"

using namespace darkroom;

// Linear Rec.709 of a reflectance spectrum under D65, through the same CMFs.
static std::array<double, 3> rgb_of(const Spectrum& reflectance) {
    const auto cmf = cie1931_cmf();
    const Spectrum light = illuminant_d65();
    double xyz[3] = {0, 0, 0}, white_y = 0;
    for (int i = 0; i < kSpectralSamples; ++i) {
        for (int k = 0; k < 3; ++k) xyz[k] += cmf[k][i] * light[i] * reflectance[i];
        white_y += cmf[1][i] * light[i];
    }
    for (double& v : xyz) v /= white_y;
    return {3.2406 * xyz[0] - 1.5372 * xyz[1] - 0.4986 * xyz[2], -0.9689 * xyz[0] + 1.8758 * xyz[1] + 0.0415 * xyz[2],
            0.0557 * xyz[0] - 0.2040 * xyz[1] + 1.0570 * xyz[2]};
}

TEST_CASE("the RGB basis spectra reproduce their primaries", "[spectral]") {
    const auto& basis = rgb_basis_spectra();
    for (int c = 0; c < 3; ++c) {
        auto rgb = rgb_of(basis[c]);
        for (int k = 0; k < 3; ++k) CHECK(rgb[k] == Approx(c == k ? 1.0 : 0.0).margin(1e-9));
    }
}

TEST_CASE("CMFs peak where CIE 1931 does", "[spectral]") {
    const auto cmf = cie1931_cmf();
    int peak = 0;
    for (int i = 0; i < kSpectralSamples; ++i)
        if (cmf[1][i] > cmf[1][peak]) peak = i;
    CHECK(wavelength_nm(peak) == Approx(555).margin(10));
}

TEST_CASE("exposure weights follow the emulsion's spectral sensitivity", "[spectral]") {
    const Spectrum light = illuminant_d65();
    auto blue = rgb_exposure_weights(emulsion_sensitivity(Emulsion::blue_sensitive), light);
    auto ortho = rgb_exposure_weights(emulsion_sensitivity(Emulsion::orthochromatic), light);
    auto pan = rgb_exposure_weights(emulsion_sensitivity(Emulsion::panchromatic), light);
    for (const auto& w : {blue, ortho, pan}) CHECK(w[0] + w[1] + w[2] == Approx(1.0));
    CHECK(blue[2] > 0.8);                  // blue-sensitive: blue light does the exposing
    CHECK(ortho[1] > ortho[0] + 0.2);      // orthochromatic: green yes, red hardly
    CHECK(pan[0] > ortho[0] + 0.1);        // panchromatic: red as well
    // The weights are the spectral integral: a narrow band at one wavelength exposes in
    // proportion to the sensitivity there.
    const Spectrum s = emulsion_sensitivity(Emulsion::panchromatic);
    CHECK(s[wavelength_index(700)] < 0.05);
    CHECK(s[wavelength_index(625)] > 0.5);
}
