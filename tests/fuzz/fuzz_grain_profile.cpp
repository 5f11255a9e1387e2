// Grain profiles (core/plate/grain_profile.h). Rejection is a GrainProfileError; an accepted
// profile satisfies validate_grain_profile, and grain_profile_to_json (which also derives
// the noise-equivalent area and half-power frequency from it) writes a file that reads
// back as the same profile; planned for synthesis (or refused with a GrainProfileError) it
// puts grain on a frame that stays finite wherever the frame is (fuzz_render.h), or refuses
// the frame's channels with a UserError.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/plate/grain_profile.h"
#include "tests/fuzz/fuzz_check.h"
#include "tests/fuzz/fuzz_render.h"

using namespace darkroom;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    GrainProfile profile;
    try {
        profile = parse_grain_profile_json(text, "fuzz input");
    } catch (const GrainProfileError&) {
        return 0;
    }
    validate_grain_profile(profile, "the parsed fuzz input");
    for (const GrainChannel& channel : profile.channels)
        for (double level : channel.level) fuzz_require(std::isfinite(channel.sigma_at(level)));

    const GrainProfile written = parse_grain_profile_json(grain_profile_to_json(profile), "the fuzz input, written");
    fuzz_require(written.encoding == profile.encoding && written.colorspace == profile.colorspace);
    fuzz_require(written.channels.size() == profile.channels.size());
    for (size_t c = 0; c < profile.channels.size(); ++c) {
        const GrainChannel &a = profile.channels[c], &b = written.channels[c];
        fuzz_require(a.name == b.name && a.level == b.level && a.sigma == b.sigma && a.samples == b.samples);
        fuzz_require(a.acf_radius == b.acf_radius && a.autocorrelation == b.autocorrelation);
    }
    fuzz_require(written.channel_correlation == profile.channel_correlation);
    try {
        fuzz_require(darkroom::fuzz::grains_finite(plan_grain_synthesis(profile)));
    } catch (const GrainProfileError&) {
    } catch (const UserError&) {
    }
    return 0;
}
