#include "core/plate/grain_prediction.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/stages/grain.h"

namespace darkroom {

namespace {

constexpr int kPredictedLevels = 25;
constexpr int kMaxPredictedAcfRadius = 32;

}  // namespace

GrainProfile predict_grain_profile(const Stock& stock, const ScanGeometry& scan) {
    if (scan.width_px < 1) throw std::invalid_argument("the scan width must be at least 1 pixel");
    if (stock.layers.empty()) throw std::invalid_argument("stock '" + stock.id + "' has no layers");
    const double frame_mm = scan.frame_width_mm > 0 ? scan.frame_width_mm : stock.frame_width_mm;
    const double pitch_um = frame_mm * 1000.0 / scan.width_px;

    GrainProfile profile;
    profile.colorspace = "Cineon log";
    profile.encoding = SignalEncoding::log;
    std::ostringstream source;
    source << stock.id << " scanned at " << scan.width_px << " px across " << frame_mm << " mm, ";
    if (scan.balance)
        source << "balanced: a normally exposed mid grey at code " << scan.aim_code;
    else
        source << "unbalanced: each layer's base+fog at code " << kScanBaseCode;
    profile.sources.push_back(source.str());
    for (size_t l = 0; l < stock.layers.size(); ++l) {
        const Layer& layer = stock.layers[l];
        const double d_min = layer.density_curve.y_min();
        const double base = scan_base_density(stock, l, scan.balance, scan.aim_code);
        GrainModel model = design_grain(layer.grain, d_min, pitch_um, NoiseKey{});
        GrainChannel ch;
        ch.name = layer.name;
        // From D-min (or code 0, where a low aim puts D-min below it) to the top of the curve,
        // but never past code 1023.
        const double net_min = std::max(0.0, base - kScanBaseCode * kScanDensityPerCode - d_min);
        const double net_max = std::min(layer.density_curve.y_max() - d_min,
                                        base + (kMaxScanCode - kScanBaseCode) * kScanDensityPerCode - d_min);
        if (!(net_max > net_min))
            throw std::invalid_argument("a scan aim of code " + std::to_string(scan.aim_code) + " puts stock '" +
                                        stock.id + "' outside codes 0-1023");
        for (int i = 0; i < kPredictedLevels; ++i) {
            const double net = net_min + (net_max - net_min) * i / (kPredictedLevels - 1);
            ch.level.push_back(scan_level(d_min + net, base));
            double density_sigma = model.pixel_sigma_at_unit_density() * std::pow(net, model.density_exponent);
            ch.sigma.push_back(density_sigma / (kScanDensityPerCode * kMaxScanCode));
        }
        // Autocorrelation of the separable kernel: a(dx) a(dy) / a(0)^2.
        const int kr = model.radius;
        ch.acf_radius = std::min(2 * kr, kMaxPredictedAcfRadius);
        std::vector<double> a(2 * ch.acf_radius + 1, 0.0);
        for (int d = -ch.acf_radius; d <= ch.acf_radius; ++d)
            for (int i = 0; i < (int)model.kernel.size(); ++i) {
                int j = i + d;
                if (j >= 0 && j < (int)model.kernel.size()) a[d + ch.acf_radius] += double(model.kernel[i]) * model.kernel[j];
            }
        const double a0 = a[ch.acf_radius];
        ch.autocorrelation.clear();
        for (int dy = -ch.acf_radius; dy <= ch.acf_radius; ++dy)
            for (int dx = -ch.acf_radius; dx <= ch.acf_radius; ++dx)
                ch.autocorrelation.push_back(a[dx + ch.acf_radius] * a[dy + ch.acf_radius] / (a0 * a0));
        profile.channels.push_back(std::move(ch));
    }
    if (profile.channels.size() == 1) {
        const char* names[3] = {"R", "G", "B"};
        GrainChannel grey = profile.channels.front();
        profile.channels.clear();
        for (const char* name : names) {
            profile.channels.push_back(grey);
            profile.channels.back().name = name;
        }
        profile.channel_correlation.assign(9, 1.0);
    } else {
        const size_t n = profile.channels.size();
        profile.channel_correlation.assign(n * n, 0.0);
        for (size_t i = 0; i < n; ++i) profile.channel_correlation[i * n + i] = 1.0;
    }
    validate_grain_profile(profile, "predicted profile for " + stock.id);
    return profile;
}

}  // namespace darkroom
