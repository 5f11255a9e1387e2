#include "core/quality.h"

namespace darkroom {

namespace {

// The settings of each tier; `darkroom bench` measures what each costs and how far it is
// from the reference (docs/development/quality-tiers.md).
constexpr QualityTier kTiers[] = {
    {Quality::reference, "reference", {0, 0.0}, 1, 1, GrainMethod::boolean_model, 0, 0, 0},
    {Quality::high, "high", {0, kSeparableTolerance}, 1, 1, GrainMethod::filtered_noise, 0, 0, 0},
    {Quality::fast, "fast", {3, 1e-3, 2, true}, 8, 8, GrainMethod::hashed_noise, 65, 6, 0},
    // fast's stages on a proxy of at most 2^20 pixels (about 1 MP)
    {Quality::preview, "preview", {3, 1e-3, 2, true}, 8, 8, GrainMethod::hashed_noise, 65, 6, 1LL << 20},
};

}  // namespace

const QualityTier& quality_tier(Quality q) { return kTiers[int(q)]; }

int proxy_factor(const QualityTier& tier, int film_width_px, int film_height_px) {
    if (tier.proxy_pixel_budget <= 0) return 1;
    auto proxy_pixels = [&](long long n) {
        return ((film_width_px + n - 1) / n) * ((film_height_px + n - 1) / n);
    };
    int n = 2;
    while (proxy_pixels(n) > tier.proxy_pixel_budget) ++n;
    return n;
}

const char* quality_name(Quality q) { return quality_tier(q).name; }

std::optional<Quality> parse_quality(const std::string& name) {
    for (const QualityTier& t : kTiers)
        if (name == t.name) return t.quality;
    return std::nullopt;
}

}  // namespace darkroom
