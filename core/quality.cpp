#include "core/quality.h"

namespace darkroom {

namespace {

// The settings of each tier; `darkroom bench` measures what each costs and how far it is
// from the reference (docs/development/quality-tiers.md).
constexpr QualityTier kTiers[] = {
    {Quality::reference, "reference", {0, 0.0}, 1, 1, GrainMethod::boolean_model, 0, 0, 1},
    {Quality::high, "high", {0, kSeparableTolerance}, 1, 1, GrainMethod::filtered_noise, 0, 0, 1},
    {Quality::fast, "fast", {3, 1e-3, 2, true}, 8, 8, GrainMethod::hashed_noise, 65, 6, 1},
    // fast's stages on the proxy
    {Quality::preview, "preview", {3, 1e-3, 2, true}, 8, 8, GrainMethod::hashed_noise, 65, 6, 2},
};

}  // namespace

const QualityTier& quality_tier(Quality q) { return kTiers[int(q)]; }

const char* quality_name(Quality q) { return quality_tier(q).name; }

std::optional<Quality> parse_quality(const std::string& name) {
    for (const QualityTier& t : kTiers)
        if (name == t.name) return t.quality;
    return std::nullopt;
}

}  // namespace darkroom
