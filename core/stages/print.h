// Printing: the enlarger's light through the developed negative onto the layers of a
// paper or print film, and viewing the developed print.
//
// The negative's spectral density is D(l) = base(l) + sum_i net_i dye_i(l) (stock.h); its
// transmittance 10^-D(l) filters the lamp (a 3200 K tungsten blackbody) times the colour
// filtration F(l). Paper layer j receives
//   H_j = k_j * sum_l L(l) F(l) 10^-D(l) S_j(l) / sum_l L(l) S_j(l)      (5 nm rectangle rule)
// with k_j its printer light in lux-seconds through a clear, unfiltered path. The
// developed print's spectral density gives its reflectance (or a print film's
// transmittance) R(l) = 10^-Dp(l), viewed under CIE D65 and expressed in linear Rec.709
// (PrintView says how: as the eye adapted to the print's own white sees it, or absolute).
//
// Automatic printer lights: the dye amounts of a neutral print of visual density
// `mid_grey_aim_density` (neutral as the print is viewed, at the luminance 10^-aim) are
// solved for; each
// paper layer's light k_j is set so that the negative of a scene mid grey exposed at 0 EV
// gives that layer exactly its aim density. Printer points then scale k_j by
// 10^(0.025 (points - 25)); print exposure by 2^EV.
//
// Where every dye of the negative (or the paper) is spectrally flat (black-and-white
// silver), the spectral integral is exactly a scalar and the plan uses that.
#pragma once

#include <array>
#include <string>

#include "core/spectral.h"
#include "core/stages/tables.h"
#include "core/stock.h"

namespace darkroom {

// Idealised Kodak-style colour printing filters, density per CC unit / 100 at each
// wavelength: yellow absorbs blue, magenta green, cyan red (smooth band edges at about
// 500 and 590 nm); not any one maker's measured filters.
std::array<Spectrum, 3> filtration_densities();

// How a developed print is seen (PrintView).
enum class PrintViewing {
    // As a viewer sees a print: adapted to its own white (the base of a projected print
    // film, the paper white under its light), and placed so that the automatic print of a
    // scene mid grey is 0.18 on every paper, as the scene's was.
    media_relative,
    // Its colorimetry under D65 as it is, a perfect white (R = 1) at (1, 1, 1): the base's
    // colour shows, and mid grey lands at 10^-aim (0.10 on print film, 0.18 on paper).
    absolute,
};
struct ViewSettings {
    PrintViewing viewing = PrintViewing::media_relative;
    bool compress_gamut = true;  // compress_to_gamut (spectral.h) on the result
};

struct PrintSettings {
    double mid_grey_film_exposure_lux_s = 0;   // what a scene mid grey at 0 EV gave the film
    std::array<double, 3> printer_lights{25.0, 25.0, 25.0};
    std::array<double, 3> filtration_ymc{0.0, 0.0, 0.0};
    double print_exposure_ev = 0.0;
    ViewSettings view;
};

class PrintExposure {
public:
    // Throws std::invalid_argument when the paper cannot reach its aim density.
    static PrintExposure design(const Stock& film, const Stock& paper, const PrintSettings& settings);

    // Paper layer exposures (lux-seconds) from the negative's layer densities. Per pixel.
    void expose(const double* negative_density, double* paper_exposure_lux_s) const;
    // The negative's spectral transmittance is a product over its layers, 10^-base times
    // 10^-(D_l - d_min_l) dye_l for each l: a grid of negatives (the fast tiers' print table)
    // takes one layer's factor per axis node, where expose() takes an exponential a wavelength
    // a negative. One layer's factor at its density D_l (layer 0's carries the base):
    Spectrum layer_transmittance(int layer, double density) const;
    // and expose() of the negative whose layers' factors these are (spectral() only).
    void expose(const std::array<const Spectrum*, 3>& layer_transmittance, double* paper_exposure_lux_s) const;
    // The same for `stride` negatives that share their layers 1 and 2's factors, layer 0's
    // given transposed (layer0[s * stride + i]: sample s of negative i's), into
    // paper_exposure_lux_s[j * stride + i] for paper layer j: a row of the print table's grid,
    // in vectors of negatives (each one's sum over the samples in their order, so any vector
    // width gives the same values), summed in floats for twice the lanes: within 81 float
    // roundings of expose()'s (1e-5 relative, 1e-5 D on the paper). stride: a multiple of
    // kRowStride (the row's nodes and copies after them). spectral(), three film and three
    // paper layers only.
    static constexpr int kRowStride = 16;
    void expose_row(const float* layer0, int stride, const Spectrum& layer1, const Spectrum& layer2,
                    double* paper_exposure_lux_s) const;

    int paper_layers() const { return paper_layers_; }
    bool spectral() const { return !neutral_negative_; }
    // Paper layer densities of the neutral mid-grey print, and the lights that give it.
    const std::array<double, 3>& aim_density() const { return aim_density_; }
    // How the print is seen; the neutral aim is neutral as seen so.
    const ViewSettings& view() const { return view_; }
    const std::array<double, 3>& light_lux_s() const { return light_lux_s_; }
    // The bytes of everything expose() reads (the film's dyes and base, the lights, the
    // filtration): exposures with equal fingerprints expose every negative alike.
    std::string fingerprint() const;
    // The same enlarger with every light 1 lux-second: the printer lights and print exposure
    // only scale each paper layer's exposure (light_lux_s), so this one's exposures times
    // light_lux_s are this enlarger's, for any lights (the fast tiers' print tables keep
    // the paper's log exposures of a grid of negatives by its fingerprint).
    PrintExposure at_unit_lights() const;

private:
    // The negative's spectral density: base + sum_i (D_i - d_min_i) dye_i.
    Spectrum film_base_{};
    std::array<Spectrum, 3> film_dye_{};
    std::array<double, 3> film_d_min_{};
    int film_layers_ = 1, paper_layers_ = 1;
    bool neutral_negative_ = true;
    // Per paper layer: the normalised light L F S_j / sum L S_j times k_j, and its sum; and
    // the same at k_j = 1.
    std::array<Spectrum, 3> weighted_light_{}, unit_light_{};
    std::array<double, 3> neutral_light_{}, neutral_unit_light_{};
    std::array<double, 3> aim_density_{}, light_lux_s_{};
    ViewSettings view_;
};

// Viewing a developed print: its layer densities -> spectral reflectance (or a print
// film's transmittance) 10^-Dp(l) -> colour under D65, c = reflectance_to_linear_srgb(R) ->
//   absolute         c
//   media-relative   g M c,  M = adaptation_to_d65(w), g = 0.18 10^aim
// w the colour of the print's white (every layer at its minimum density: the base and fog),
// M the eye's adaptation from it to D65 keeping its luminance (a black-and-white print is
// neutral: M = 1), aim the paper's mid_grey_aim_density; a neutral print of visual density
// aim, which the automatic lights give a scene mid grey, is then 0.18 whatever the paper,
// and the base is neutral at 0.18 10^(aim - D_base), D_base its visual density: about 1.55
// on Kodak 2383 (a projected print's highlights, the room dark), 0.8 to 0.9 on paper.
// Then, when the settings say so, compress_to_gamut.
class PrintView {
public:
    PrintView(const Stock& paper, const ViewSettings& settings);
    // Linear Rec.709. Per pixel.
    void rgb(const double* paper_density, double* rgb) const;
    // Where a neutral print of the paper's aim density lands (each component).
    double mid_grey() const { return mid_grey_; }
    // A colour print's rgb() before the gamut compression is xyz_to_rgb() times its CIE XYZ
    // under D65 (a perfect white's Y 1), which, unlike the rgb of a saturated colour, is never
    // negative (print_view_table holds its cube roots). Per pixel.
    Xyz xyz(const double* paper_density) const;
    const Matrix3& xyz_to_rgb() const { return xyz_to_rgb_; }

private:
    Spectrum reflectance(const double* paper_density) const;
    const Stock* paper_;
    std::array<double, 3> d_min_{};
    ViewSettings settings_;
    Matrix3 view_{};  // g M (the identity when absolute)
    Matrix3 xyz_to_rgb_{};
    double mid_grey_ = 0;
};

// PrintView of a colour paper, without the gamut compression (whose knee an interpolant would
// round off), as a table over its layers' densities from each one's minimum to its maximum
// (all its curves give): the print's XYZ held as cube roots (Table3D, `nodes` per axis,
// built on `threads` threads), and the matrix to linear Rec.709. The XYZ is a sum of
// exponentials of the densities, always positive, and its cube root bends little between
// nodes; an rgb channel's cube root would turn vertical where a saturated colour crosses 0
// (the error, tests/core/test_quality.cpp: CIEDE2000 max 0.08, mean 0.009 at 65 nodes, where
// tabulating the rgb gave 0.48 and 0.013).
struct PrintViewTable {
    Table3D xyz;
    Matrix3 xyz_to_rgb{};
};
PrintViewTable print_view_table(const Stock& paper, PrintViewing viewing, int nodes, int threads);

}  // namespace darkroom
