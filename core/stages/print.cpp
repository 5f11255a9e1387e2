#include "core/stages/print.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/simd.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

namespace {

constexpr double kLn10 = 2.302585092994046;
constexpr double kLogExposurePerPoint = 0.025;
constexpr double kMidGrey = 0.18;  // a scene mid grey, scene-linear
const Spectrum kEnlargerLamp = blackbody(3200.0);

double logistic(double x) { return 1.0 / (1.0 + std::exp(-x)); }

bool is_flat(const Spectrum& s) {
    for (double v : s)
        if (v != s[0]) return false;
    return true;
}

// The paper layer densities whose print is neutral at visual density `aim` as `viewing`
// sees it: Newton's method on log10(rgb) = log10(mid grey) with a finite-difference Jacobian.
std::array<double, 3> neutral_print_densities(const Stock& paper, double aim, PrintViewing viewing) {
    const int n = int(paper.layers.size());
    std::array<double, 3> d{};
    for (int j = 0; j < n; ++j) d[j] = paper.layers[j].density_curve.y_min() + aim;
    if (n == 1) {
        d[0] = aim;  // a neutral silver print: its visual density is its density
        return d;
    }
    // (Without gamut compression: it leaves near-neutral colours as they are.)
    const PrintView view(paper, {viewing, false});
    const double log_grey = std::log10(view.mid_grey());
    auto residual = [&](const std::array<double, 3>& at) {
        double rgb[3];
        view.rgb(at.data(), rgb);
        std::array<double, 3> f;
        for (int k = 0; k < 3; ++k) f[k] = log_grey - std::log10(std::max(rgb[k], 1e-300));
        return f;
    };
    for (int iteration = 0; iteration < 100; ++iteration) {
        std::array<double, 3> f = residual(d);
        if (std::max({std::abs(f[0]), std::abs(f[1]), std::abs(f[2])}) < 1e-10) return d;
        double jac[3][3];
        for (int j = 0; j < 3; ++j) {
            std::array<double, 3> step = d;
            step[j] += 1e-6;
            std::array<double, 3> g = residual(step);
            for (int k = 0; k < 3; ++k) jac[k][j] = (g[k] - f[k]) / 1e-6;
        }
        // Solve jac * delta = f by Cramer's rule (3x3).
        auto det3 = [](double m[3][3]) {
            return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                   m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        };
        double det = det3(jac);
        if (!(std::abs(det) > 1e-12)) break;
        for (int j = 0; j < 3; ++j) {
            double m[3][3];
            for (int k = 0; k < 3; ++k)
                for (int l = 0; l < 3; ++l) m[k][l] = l == j ? f[k] : jac[k][l];
            d[j] -= std::clamp(det3(m) / det, -0.5, 0.5);
        }
    }
    throw std::invalid_argument("paper '" + paper.id + "': its dyes cannot make a neutral grey of density " +
                                std::to_string(aim));
}

// The luminance of a reversal film's normally exposed mid grey (the exposure its speed
// implies), viewed absolute.
double slide_mid_grey_luminance(const Stock& film) {
    const double log_h = std::log10(mid_grey_exposure_lux_s(film.iso_speed));
    double density[3] = {0, 0, 0};
    for (size_t l = 0; l < film.layers.size() && l < 3; ++l) density[l] = film.layers[l].density_curve(log_h);
    return luminance(reflectance_to_linear_srgb(transmittance_of(spectral_density(film, density))));
}

// Dot products of `stride` spectra, given transposed (spectra[s * stride + i]), with each of
// three spectra (with[j * kSpectralSamples + s]), into out[j * stride + i], in floats (twice
// the lanes of doubles), each summed over the samples in their order: four vectors of spectra
// at a time against all three (twelve chains of sums in flight, each vector loaded once),
// then one. stride: a multiple of every vector's lanes, so there is no scalar tail.
static_assert(PrintExposure::kRowStride % simd::kAvx512Lanes == 0 && simd::kAvx512Lanes % simd::kAvx2Lanes == 0 &&
                  simd::kAvx2Lanes % simd::kBaselineLanes == 0,
              "a row's stride is whole vectors at every instruction set");
struct DotsWithThree {
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* spectra, int stride, const float* with, double* out) {
        using F = typename simd::Lanes<lanes>::F;
        int i = 0;
        for (; i + 4 * lanes <= stride; i += 4 * lanes) dots<F, 4>(spectra, stride, with, out, i);
        for (; i < stride; i += lanes) dots<F, 1>(spectra, stride, with, out, i);
    }
    template <typename F, int vectors>
    __attribute__((always_inline)) static void dots(const float* spectra, int stride, const float* with, double* out,
                                                    int i) {
        constexpr int lanes = sizeof(F) / sizeof(float);
        F sum[3][vectors]{};
        for (int s = 0; s < kSpectralSamples; ++s) {
            F t[vectors];
            for (int v = 0; v < vectors; ++v) simd::load(t[v], spectra + size_t(s) * size_t(stride) + size_t(i + v * lanes));
            for (int j = 0; j < 3; ++j)
                for (int v = 0; v < vectors; ++v) sum[j][v] += t[v] * with[j * kSpectralSamples + s];
        }
        for (int j = 0; j < 3; ++j)
            for (int v = 0; v < vectors; ++v)
                for (int l = 0; l < lanes; ++l) out[size_t(j) * size_t(stride) + size_t(i + v * lanes + l)] = double(sum[j][v][l]);
    }
};

}  // namespace

std::array<Spectrum, 3> filtration_densities() {
    std::array<Spectrum, 3> f;
    for (int i = 0; i < kSpectralSamples; ++i) {
        double nm = wavelength_nm(i);
        f[0][i] = logistic((500.0 - nm) / 8.0);                               // yellow: blue
        f[1][i] = logistic((nm - 500.0) / 8.0) * logistic((590.0 - nm) / 8.0);  // magenta: green
        f[2][i] = logistic((nm - 590.0) / 8.0);                               // cyan: red
    }
    return f;
}

PrintExposure PrintExposure::design(const Stock& film, const Stock& paper, const PrintSettings& settings) {
    PrintExposure p;
    p.film_layers_ = int(film.layers.size());
    p.paper_layers_ = int(paper.layers.size());
    p.film_base_ = film.base_density;
    p.neutral_negative_ = is_flat(film.base_density);
    for (int i = 0; i < p.film_layers_; ++i) {
        p.film_dye_[i] = film.layers[i].dye_density;
        p.film_d_min_[i] = film.layers[i].density_curve.y_min();
        p.neutral_negative_ = p.neutral_negative_ && is_flat(p.film_dye_[i]);
    }

    // The negative of a mid grey: every film layer got the same exposure (neutral light).
    double grey_density[3];
    for (int i = 0; i < p.film_layers_; ++i)
        grey_density[i] = film.layers[i].density_curve(std::log10(settings.mid_grey_film_exposure_lux_s));
    const Spectrum grey_transmittance = transmittance_of(spectral_density(film, grey_density));

    p.view_ = settings.view;
    p.aim_density_ = neutral_print_densities(paper, paper.mid_grey_aim_density, settings.view.viewing);
    const std::array<Spectrum, 3> filters = filtration_densities();
    double mean_points = (settings.printer_lights[0] + settings.printer_lights[1] + settings.printer_lights[2]) / 3.0;
    for (int j = 0; j < p.paper_layers_; ++j) {
        const Layer& layer = paper.layers[j];
        double norm = 0, grey_exposure = 0;
        for (int i = 0; i < kSpectralSamples; ++i) norm += kEnlargerLamp[i] * layer.sensitivity[i];
        for (int i = 0; i < kSpectralSamples; ++i) {
            p.weighted_light_[j][i] = kEnlargerLamp[i] * layer.sensitivity[i] / norm;
            grey_exposure += p.weighted_light_[j][i] * grey_transmittance[i];
        }
        double log_h_aim;
        if (!layer.density_curve.first_x_at(p.aim_density_[j], &log_h_aim))
            throw std::invalid_argument("paper '" + paper.id + "' layer " + layer.name +
                                        " never reaches the density of a neutral mid grey (" +
                                        std::to_string(p.aim_density_[j]) + ")");
        // A single-layer paper has one light: the mean of the three.
        double points = p.paper_layers_ == 1 ? mean_points : settings.printer_lights[j];
        p.light_lux_s_[j] = std::pow(10.0, log_h_aim) / grey_exposure *
                            std::pow(10.0, kLogExposurePerPoint * (points - 25.0)) *
                            std::exp2(settings.print_exposure_ev);
        p.neutral_light_[j] = p.neutral_unit_light_[j] = 0;
        for (int i = 0; i < kSpectralSamples; ++i) {
            double filtration = settings.filtration_ymc[0] * filters[0][i] + settings.filtration_ymc[1] * filters[1][i] +
                                settings.filtration_ymc[2] * filters[2][i];
            p.unit_light_[j][i] = p.weighted_light_[j][i] * std::pow(10.0, -filtration / 100.0);
            p.weighted_light_[j][i] = p.unit_light_[j][i] * p.light_lux_s_[j];
            p.neutral_unit_light_[j] += p.unit_light_[j][i];
            p.neutral_light_[j] += p.weighted_light_[j][i];
        }
    }
    return p;
}

void PrintExposure::expose(const double* negative_density, double* paper_exposure) const {
    if (neutral_negative_) {
        double t = std::exp(-kLn10 * (film_base_[0] + negative_density[0] - film_d_min_[0]));
        for (int j = 0; j < paper_layers_; ++j) paper_exposure[j] = neutral_light_[j] * t;
        return;
    }
    double net[3];
    for (int l = 0; l < film_layers_; ++l) net[l] = negative_density[l] - film_d_min_[l];
    Spectrum d = film_base_;
    for (int l = 0; l < film_layers_; ++l) add_scaled(d, net[l], film_dye_[l]);
    const Spectrum t = transmittance_of(d);
    for (int j = 0; j < paper_layers_; ++j) paper_exposure[j] = dot(weighted_light_[j], t);
}

Spectrum PrintExposure::layer_transmittance(int layer, double density) const {
    const double net = density - film_d_min_[layer];
    Spectrum d = layer == 0 ? film_base_ : Spectrum{};
    add_scaled(d, net, film_dye_[layer]);
    return transmittance_of(d);
}

void PrintExposure::expose(const std::array<const Spectrum*, 3>& layer_transmittance, double* paper_exposure) const {
    Spectrum t = *layer_transmittance[0];
    for (int l = 1; l < film_layers_; ++l)
        for (int i = 0; i < kSpectralSamples; ++i) t[i] *= (*layer_transmittance[l])[i];
    for (int j = 0; j < paper_layers_; ++j) paper_exposure[j] = dot(weighted_light_[j], t);
}

void PrintExposure::expose_row(const float* layer0, int stride, const Spectrum& layer1, const Spectrum& layer2,
                               double* paper_exposure) const {
    // Each paper layer's light through the negative's layers 1 and 2.
    std::array<float, 3 * kSpectralSamples> through;
    for (int j = 0; j < 3; ++j)
        for (int s = 0; s < kSpectralSamples; ++s)
            through[size_t(j * kSpectralSamples + s)] = float(weighted_light_[j][s] * layer1[s] * layer2[s]);
    simd::dispatch<DotsWithThree>(layer0, stride, static_cast<const float*>(through.data()), paper_exposure);
}

std::string PrintExposure::fingerprint() const {
    std::string bytes;
    auto append = [&](const auto& v) { bytes.append(reinterpret_cast<const char*>(&v), sizeof v); };
    append(film_base_), append(film_dye_), append(film_d_min_), append(film_layers_), append(paper_layers_);
    append(neutral_negative_), append(weighted_light_), append(neutral_light_), append(aim_density_),
        append(light_lux_s_), append(view_.viewing), append(view_.compress_gamut);
    return bytes;
}

PrintExposure PrintExposure::at_unit_lights() const {
    PrintExposure p = *this;
    p.weighted_light_ = unit_light_;
    p.neutral_light_ = neutral_unit_light_;
    p.light_lux_s_ = {1.0, 1.0, 1.0};
    return p;
}

PrintView::PrintView(const Stock& paper, const ViewSettings& settings) : paper_(&paper), settings_(settings) {
    for (size_t l = 0; l < paper.layers.size() && l < 3; ++l) d_min_[l] = paper.layers[l].density_curve.y_min();
    // A slide has no aim density: its mid grey is where a normally exposed one developed.
    const double absolute_grey =
        paper.kind == StockKind::reversal ? slide_mid_grey_luminance(paper) : std::pow(10.0, -paper.mid_grey_aim_density);
    Matrix3 adaptation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    double gain = 1;
    if (settings.viewing == PrintViewing::media_relative) {
        if (paper.is_colour()) adaptation = adaptation_to_d65(reflectance_to_linear_srgb(reflectance(d_min_.data())));
        gain = kMidGrey / absolute_grey;
    }
    for (auto& row : adaptation)
        for (double& v : row) v *= gain;
    view_ = adaptation;
    mid_grey_ = gain * absolute_grey;
    // reflectance_to_linear_srgb: kXyzToLinearSrgb's rows scaled so that white is (1, 1, 1).
    const Rgb white = multiply(kXyzToLinearSrgb, white_point_xyz(illuminant_d65()));
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k) xyz_to_rgb_[r][c] += view_[r][k] * kXyzToLinearSrgb[k][c] / white[k];
}

Xyz PrintView::xyz(const double* paper_density) const {
    static const Spectrum d65 = illuminant_d65();
    return reflectance_to_xyz(reflectance(paper_density), d65);
}

Spectrum PrintView::reflectance(const double* paper_density) const {
    return transmittance_of(spectral_density(*paper_, paper_density, d_min_.data()));
}

void PrintView::rgb(const double* paper_density, double* rgb) const {
    Rgb out;
    if (!paper_->is_colour()) {
        const double r = view_[0][0] * std::pow(10.0, -paper_density[0]);
        out = {r, r, r};
    } else {
        out = multiply(view_, reflectance_to_linear_srgb(reflectance(paper_density)));
        if (settings_.compress_gamut) out = compress_to_gamut(out);
    }
    for (int k = 0; k < 3; ++k) rgb[k] = out[k];
}

PrintViewTable print_view_table(const Stock& paper, PrintViewing viewing, int nodes, int threads) {
    const PrintView view(paper, {viewing, false});
    std::array<double, 3> lo{}, hi{};
    for (size_t a = 0; a < 3; ++a) {
        const Curve& curve = paper.layers[a].density_curve;
        lo[a] = curve.y_min();
        hi[a] = std::max(curve.y_max(), lo[a] + 1e-3);  // (a flat curve: a grid that still has a spacing)
    }
    Table3D xyz(lo, hi, nodes, threads, [&](const int*, const double* density, double* out) {
        const Xyz v = view.xyz(density);
        std::copy(v.begin(), v.end(), out);
    }, Table3D::Encoding::cube_root);
    return {std::move(xyz), view.xyz_to_rgb()};
}

}  // namespace darkroom
