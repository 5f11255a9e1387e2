// How a print is seen (media-relative or absolute), its gamut compression, and the scan's
// balance to an aim (its definition on every pixel: test_colour.cpp).
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/develop.h"
#include "core/sensitometry.h"
#include "core/spectral.h"
#include "test_support.h"

using namespace darkroom;

namespace {

using test::render;

DevelopSettings flat_patch_settings(Quality quality = Quality::high) {
    DevelopSettings s;
    s.quality = quality;
    s.grain = s.mtf = false;
    s.halation = 0;
    return s;
}

double chroma(const Rgb& rgb) {
    const Lab lab = xyz_to_lab(linear_srgb_to_xyz(rgb), linear_srgb_to_xyz({1, 1, 1}));
    return std::hypot(lab[1], lab[2]);
}

std::vector<const Stock*> stocks_of(const std::vector<StockKind>& kinds) {
    std::vector<const Stock*> out;
    for (const Stock& s : builtin_stocks())
        if (std::find(kinds.begin(), kinds.end(), s.kind) != kinds.end()) out.push_back(&s);
    return out;
}

const std::vector<StockKind> kNegatives = {StockKind::negative};
const std::vector<StockKind> kPrintMaterials = {StockKind::paper, StockKind::print_film};

}  // namespace

TEST_CASE("adapting to a white makes that white neutral at its own luminance, and D65 is left alone",
          "[spectral][viewing]") {
    for (Rgb white : {Rgb{0.9, 0.8, 0.6}, Rgb{0.5, 0.55, 0.4}, Rgb{0.2, 0.3, 0.5}}) {
        const Rgb adapted = multiply(adaptation_to_d65(white), white);
        for (int c = 0; c < 3; ++c) CHECK(adapted[c] == Approx(luminance(white)).epsilon(1e-12));
    }
    const Matrix3 same = adaptation_to_d65({0.7, 0.7, 0.7});
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) CHECK(same[i][j] == Approx(i == j ? 1.0 : 0.0).margin(1e-12));
    // Each channel on its own (no channel mixes into another: a colour without blue keeps none).
    const Rgb yellow = multiply(adaptation_to_d65({0.9, 0.8, 0.6}), {0.5, 0.4, 0.0});
    CHECK(yellow[2] == 0.0);
    CHECK_THROWS_WITH(adaptation_to_d65({0.5, 0.5, 0}), Catch::Contains("not positive"));
}

TEST_CASE("gamut compression keeps luminance and hue, leaves no negative component, and leaves the inner gamut "
          "alone",
          "[spectral][gamut]") {
    for (double r = -0.5; r <= 1.5; r += 0.25)
        for (double g = -0.5; g <= 1.5; g += 0.25)
            for (double b = -0.5; b <= 1.5; b += 0.25) {
                const Rgb c{r, g, b}, m = compress_to_gamut(c);
                const double y = luminance(c);
                INFO(r << " " << g << " " << b);
                if (!(y > 0)) {
                    CHECK(m == Rgb{0, 0, 0});
                    continue;
                }
                CHECK(std::min({m[0], m[1], m[2]}) >= 0);
                CHECK(luminance(m) == Approx(y).epsilon(1e-12));
                // On the line from (y, y, y) through c, not past c.
                const double distance = (y - std::min({r, g, b})) / y;
                const double k = std::abs(r - y) + std::abs(g - y) + std::abs(b - y) > 0
                                     ? (std::abs(m[0] - y) + std::abs(m[1] - y) + std::abs(m[2] - y)) /
                                           (std::abs(r - y) + std::abs(g - y) + std::abs(b - y))
                                     : 1.0;
                CHECK(k <= 1.0 + 1e-12);
                for (int i = 0; i < 3; ++i) CHECK(m[i] == Approx(y + k * (c[i] - y)).margin(1e-12));
                if (distance <= kGamutCompressionStart) CHECK(m == c);
            }
}

TEST_CASE("media-relative viewing shows the print's white neutral and a scene mid grey at 0.18 on every paper",
          "[develop][viewing]") {
    const Stock& film = find_stock("kodak-vision3-250d");
    for (const Stock* paper : stocks_of(kPrintMaterials)) {
        INFO(paper->id);
        // The base (every layer at its minimum density) seen media-relative is neutral.
        double d_min[3] = {0, 0, 0}, base[3];
        for (size_t l = 0; l < paper->layers.size(); ++l) d_min[l] = paper->layers[l].density_curve.y_min();
        PrintView(*paper, {PrintViewing::media_relative, false}).rgb(d_min, base);
        CHECK(chroma({base[0], base[1], base[2]}) < 1e-6);
        // The automatic print of a scene mid grey: 0.18 seen media-relative, 10^-aim absolute.
        for (PrintViewing viewing : {PrintViewing::media_relative, PrintViewing::absolute}) {
            DevelopSettings s = flat_patch_settings();
            s.print_viewing = viewing;
            const Rgb grey = print_grey_scale(film, *paper, s, {0.0})[0].print;
            const double expected = viewing == PrintViewing::media_relative ? 0.18 : std::pow(10.0, -paper->mid_grey_aim_density);
            for (int c = 0; c < 3; ++c) CHECK(grey[c] == Approx(expected).epsilon(1e-6));
        }
    }
    // The print film's base has a colour: absolute viewing shows it (a bright highlight prints
    // near the base), media-relative does not.
    const Stock& print_film = find_stock("kodak-2383");
    double d_min[3], absolute_base[3];
    for (int l = 0; l < 3; ++l) d_min[l] = print_film.layers[l].density_curve.y_min();
    PrintView(print_film, {PrintViewing::absolute, false}).rgb(d_min, absolute_base);
    CHECK(chroma({absolute_base[0], absolute_base[1], absolute_base[2]}) > 2);
}

TEST_CASE("the grey scale printed with the automatic lights tracks neutral within the model's curve crossovers",
          "[develop][viewing]") {
    // Black-and-white papers print every grey exactly neutral; colour pairs are neutral at
    // mid grey by construction and elsewhere within the bound set by the published curves'
    // crossovers (docs/reference/print-greys.md has the table).
    for (const Stock* film : stocks_of(kNegatives))
        for (const Stock* paper : stocks_of(kPrintMaterials)) {
            const std::vector<GreyPatch> greys = print_grey_scale(*film, *paper, flat_patch_settings(), {-2, -1, 0, 1, 2});
            INFO(film->id << " on " << paper->id);
            CHECK(greys[2].chroma < 1e-4);
            // Two papers' published curves part in the print's shadows (Ultra Endura by up to
            // 19 at -2 EV, Ektacolor Edge by up to 10, docs/reference/print-greys.md): a wider bound.
            const bool tinted_sheet = paper->id == "kodak-ultra-endura" || paper->id == "kodak-ektacolor-edge";
            const double bound = !paper->is_colour() ? 1e-6 : tinted_sheet ? 20.0 : 7.5;
            for (const GreyPatch& g : greys) CHECK(g.chroma < bound);
        }
}

TEST_CASE("gamut compression leaves no negative component on saturated prints and keep passes them through",
          "[develop][gamut]") {
    const Stock& film = find_stock("kodak-vision3-500t");
    const Stock& paper = find_stock("kodak-2383");
    Image patches(6, 1, 3);
    const Rgb colours[] = {{2, 0, 0}, {0, 2, 0}, {0, 0, 2}, {0, 1.5, 1.5}, {0.18, 0.18, 0.18}, {1.2, 1.0, 0}};
    for (int i = 0; i < 6; ++i)
        for (int c = 0; c < 3; ++c) patches.at(i, 0)[c] = float(colours[i][c]);
    for (Quality q : {Quality::high, Quality::fast}) {
        INFO(quality_name(q));
        DevelopSettings s = flat_patch_settings(q);
        s.print_gamut_compression = false;
        const Image kept = render(film, &paper, s, patches);
        s.print_gamut_compression = true;
        const Image compressed = render(film, &paper, s, patches);
        float most_negative = 0;
        for (float v : kept.pixels) most_negative = std::min(most_negative, v);
        CHECK(most_negative < -0.005f);  // (the case compression is for)
        for (float v : compressed.pixels) CHECK(v >= 0);
        for (int i = 0; i < 6; ++i) {
            const float* k = kept.at(i, 0);
            const float* m = compressed.at(i, 0);
            const Rgb kept_rgb{k[0], k[1], k[2]};
            // Its luminance kept (to the fast tier's table where it interpolates).
            CHECK(luminance({m[0], m[1], m[2]}) == Approx(luminance(kept_rgb)).epsilon(q == Quality::high ? 1e-5 : 0.02));
            if (q == Quality::high) {
                // compress_to_gamut of the kept colour, which keeps the inner gamut exactly.
                const Rgb expected = compress_to_gamut(kept_rgb);
                for (int c = 0; c < 3; ++c) CHECK(m[c] == Approx(expected[c]).margin(1e-6));
            }
        }
    }
}

TEST_CASE("a balanced scan puts a normally exposed mid grey at the aim in every channel", "[develop][scan]") {
    Image grey(4, 4, 3, 0.18f);
    for (const Stock* film : stocks_of(kNegatives))
        for (Quality q : {Quality::high, Quality::fast}) {
            INFO(film->id << " " << quality_name(q));
            DevelopSettings s = flat_patch_settings(q);
            s.output = OutputMode::scan;
            const Image scan = render(*film, nullptr, s, grey);
            for (int c = 0; c < 3; ++c) CHECK(scan.at(2, 2)[c] * kMaxScanCode == Approx(445.0).margin(2));
            s.scan_aim_code = 500;
            const Image other_aim = render(*film, nullptr, s, grey);
            for (int c = 0; c < 3; ++c) CHECK(other_aim.at(2, 2)[c] * kMaxScanCode == Approx(500).margin(2));
        }
    DevelopSettings s;
    s.output = OutputMode::scan;
    s.scan_aim_code = 2000;
    CHECK_THROWS_WITH(Plan::compile(find_stock("kodak-vision3-250d"), nullptr, s, {4, 4}), Catch::Contains("scan aim"));
}
