#include "core/plate/grain_profile.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numeric>
#include <utility>

#include "core/json_file.h"
#include "core/json_message.h"
#include "core/plate/noise_spectrum.h"

namespace darkroom {

using nlohmann::json;

const char* encoding_name(SignalEncoding e) {
    switch (e) {
        case SignalEncoding::linear: return "linear";
        case SignalEncoding::log: return "log";
        case SignalEncoding::display: return "display";
    }
    return "linear";
}

SignalEncoding encoding_of_colorspace(const std::string& colorspace, SignalEncoding fallback) {
    std::string cs = colorspace;
    for (char& c : cs) c = char(std::tolower((unsigned char)c));
    for (const char* log_word : {"log", "cineon", "adx", "acescc", "acescct"})
        if (cs.find(log_word) != std::string::npos) return SignalEncoding::log;
    for (const char* display_word : {"srgb", "rec709", "rec.709", "bt.709", "gamma", "display", "output"})
        if (cs.find(display_word) != std::string::npos) return SignalEncoding::display;
    for (const char* linear_word : {"linear", "lin_", "scene", "acescg", "aces2065"})
        if (cs.find(linear_word) != std::string::npos) return SignalEncoding::linear;
    return fallback;
}

double GrainChannel::sigma_at(double x) const {
    if (x <= level.front()) return sigma.front();
    if (x >= level.back()) return sigma.back();
    return sigma_in_segment(x, std::upper_bound(level.begin(), level.end(), x) - level.begin());
}

double GrainChannel::sigma_in_segment(double x, size_t i) const {
    double t = (x - level[i - 1]) / (level[i] - level[i - 1]);
    return sigma[i - 1] + t * (sigma[i] - sigma[i - 1]);
}

double GrainChannel::acf(int dx, int dy) const {
    if (std::abs(dx) > acf_radius || std::abs(dy) > acf_radius) return 0.0;
    return autocorrelation[(size_t)(dy + acf_radius) * (2 * acf_radius + 1) + dx + acf_radius];
}

namespace {

[[noreturn]] void fail(const std::string& origin, const std::string& field, const std::string& problem) {
    throw GrainProfileError(origin + ": field '" + field + "': " + problem);
}

// The JSON value at `key`, or an error naming the field.
const json& member(const json& obj, const std::string& key, const std::string& origin, const std::string& path) {
    std::string field = path.empty() ? key : path + "." + key;
    if (!obj.is_object()) fail(origin, path, "expected an object");
    auto it = obj.find(key);
    if (it == obj.end()) fail(origin, field, "missing");
    return *it;
}

// An integer in [min, max]. JSON integers can be larger than the C++ type, so the range is
// checked before converting (a wrapped 2^32 + 1 must not read as 1).
long long integer_value(const json& v, long long min, long long max, const std::string& origin,
                        const std::string& field) {
    bool in_range = false;
    if (v.is_number_unsigned()) {
        const unsigned long long u = v.get<unsigned long long>();
        in_range = max >= 0 && u <= (unsigned long long)max && (min <= 0 || u >= (unsigned long long)min);
    } else if (v.is_number_integer()) {
        const long long i = v.get<long long>();
        in_range = i >= min && i <= max;
    }
    if (!in_range)
        fail(origin, field,
             "expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "], got " +
                 json_for_message(v));
    return v.get<long long>();
}

double finite_number(const json& v, const std::string& origin, const std::string& field) {
    if (!v.is_number() || !std::isfinite(v.get<double>()))
        fail(origin, field, "expected a finite number, got " + json_for_message(v));
    return v.get<double>();
}

std::vector<double> number_array(const json& v, const std::string& origin, const std::string& field) {
    if (!v.is_array() || v.empty()) fail(origin, field, "expected a non-empty array of numbers");
    std::vector<double> out;
    for (size_t i = 0; i < v.size(); ++i)
        out.push_back(finite_number(v[i], origin, field + "[" + std::to_string(i) + "]"));
    return out;
}

std::string text_field(const json& obj, const std::string& key, const std::string& origin, const std::string& path) {
    const json& v = member(obj, key, origin, path);
    if (!v.is_string())
        fail(origin, path.empty() ? key : path + "." + key, "expected a string, got " + json_for_message(v));
    return v.get<std::string>();
}

}  // namespace

void validate_grain_profile(const GrainProfile& p, const std::string& origin) {
    const size_t n = p.channels.size();
    if (n == 0) fail(origin, "channels", "no channels");
    for (size_t c = 0; c < n; ++c) {
        const GrainChannel& ch = p.channels[c];
        const std::string at = "channels[" + std::to_string(c) + "]";
        if (ch.level.empty()) fail(origin, at + ".response.level", "no levels: the channel has no usable response");
        for (size_t i = 1; i < ch.level.size(); ++i)
            if (!(ch.level[i] > ch.level[i - 1]))
                fail(origin, at + ".response.level", "levels must be strictly increasing");
        if (ch.sigma.size() != ch.level.size())
            fail(origin, at + ".response.sigma",
                 std::to_string(ch.sigma.size()) + " values for " + std::to_string(ch.level.size()) + " levels");
        if (!ch.samples.empty() && ch.samples.size() != ch.level.size())
            fail(origin, at + ".response.samples",
                 std::to_string(ch.samples.size()) + " values for " + std::to_string(ch.level.size()) + " levels");
        if (!ch.plate_samples.empty() && ch.plate_samples.size() != ch.level.size())
            fail(origin, at + ".response.plate_samples",
                 std::to_string(ch.plate_samples.size()) + " values for " + std::to_string(ch.level.size()) + " levels");
        if (!ch.sigma_error.empty() && ch.sigma_error.size() != ch.level.size())
            fail(origin, at + ".response.relative_error",
                 std::to_string(ch.sigma_error.size()) + " values for " + std::to_string(ch.level.size()) + " levels");
        for (double e : ch.sigma_error)
            if (!(e >= 0)) fail(origin, at + ".response.relative_error", "must be >= 0");
        for (size_t i = 0; i < ch.level.size(); ++i) {
            if (!(std::abs(ch.level[i]) <= kMaxGrainLevel))
                fail(origin, at + ".response.level[" + std::to_string(i) + "]",
                     "must be within +-" + std::to_string((long long)kMaxGrainLevel));
            // Grain larger than the signal range (1 in code values, the level itself in a bright
            // linear highlight) is no grain: such a profile would only blow the image up.
            const double limit = std::max(1.0, std::abs(ch.level[i]));
            if (!(ch.sigma[i] >= 0 && ch.sigma[i] <= limit))
                fail(origin, at + ".response.sigma[" + std::to_string(i) + "]",
                     "must be from 0 to " + std::to_string(limit) + " (grain no larger than the signal range)");
        }
        const size_t side = 2 * (size_t)ch.acf_radius + 1;
        if (ch.acf_radius < 0 || ch.autocorrelation.size() != side * side)
            fail(origin, at + ".autocorrelation.values",
                 "expected (2 radius + 1)^2 = " + std::to_string(side * side) + " values, got " +
                     std::to_string(ch.autocorrelation.size()));
        if (std::abs(ch.acf(0, 0) - 1.0) > 1e-6)
            fail(origin, at + ".autocorrelation.values", "the value at lag 0 must be 1 (normalised)");
    }
    if (p.channel_correlation.size() != n * n)
        fail(origin, "channel_correlation", "expected a " + std::to_string(n) + " x " + std::to_string(n) + " matrix");
    for (size_t a = 0; a < n; ++a)
        for (size_t b = 0; b < n; ++b) {
            double v = p.correlation((int)a, (int)b);
            std::string field = "channel_correlation[" + std::to_string(a) + "][" + std::to_string(b) + "]";
            if (!std::isfinite(v) || std::abs(v) > 1.0) fail(origin, field, "must be within [-1, 1]");
            if (a == b && v != 1.0) fail(origin, field, "the diagonal must be 1");
            if (std::abs(v - p.correlation((int)b, (int)a)) > 1e-9) fail(origin, field, "the matrix must be symmetric");
        }
}

GrainProfile parse_grain_profile_json(const std::string& text, const std::string& origin) {
    json doc;
    try {
        doc = json::parse(text);
    } catch (const json::exception& e) {
        throw GrainProfileError(origin + ": not valid JSON: " + e.what());
    }
    if (text_field(doc, "format", origin, "") != "darkroom-grain-profile")
        fail(origin, "format", "expected \"darkroom-grain-profile\"");
    integer_value(member(doc, "version", origin, ""), GrainProfile::kFormatVersion, GrainProfile::kFormatVersion, origin,
                  "version");

    GrainProfile p;
    if (doc.contains("colorspace")) p.colorspace = text_field(doc, "colorspace", origin, "");
    std::string encoding = text_field(doc, "encoding", origin, "");
    if (encoding == "linear") p.encoding = SignalEncoding::linear;
    else if (encoding == "log") p.encoding = SignalEncoding::log;
    else if (encoding == "display") p.encoding = SignalEncoding::display;
    else fail(origin, "encoding", "expected linear, log or display, got \"" + encoding + "\"");
    if (doc.contains("sources"))
        for (const json& s : doc["sources"])
            if (s.is_string()) p.sources.push_back(s.get<std::string>());

    const json& channels = member(doc, "channels", origin, "");
    if (!channels.is_array() || channels.empty()) fail(origin, "channels", "expected a non-empty array");
    for (size_t c = 0; c < channels.size(); ++c) {
        const std::string at = "channels[" + std::to_string(c) + "]";
        const json& cj = channels[c];
        GrainChannel ch;
        ch.name = text_field(cj, "name", origin, at);
        const json& response = member(cj, "response", origin, at);
        ch.level = number_array(member(response, "level", origin, at + ".response"), origin, at + ".response.level");
        ch.sigma = number_array(member(response, "sigma", origin, at + ".response"), origin, at + ".response.sigma");
        for (auto [key, counts] : {std::pair{"samples", &ch.samples}, std::pair{"plate_samples", &ch.plate_samples}}) {
            if (!response.contains(key)) continue;
            const std::string field = at + ".response." + key;
            const json& values = response[key];
            if (!values.is_array()) fail(origin, field, "expected an array of pixel counts");
            for (size_t i = 0; i < values.size(); ++i)
                counts->push_back(integer_value(values[i], 0, LLONG_MAX, origin, field + "[" + std::to_string(i) + "]"));
        }
        if (response.contains("relative_error"))
            ch.sigma_error = number_array(response["relative_error"], origin, at + ".response.relative_error");
        if (cj.contains("clipped_samples"))
            ch.clipped_samples = integer_value(cj["clipped_samples"], 0, LLONG_MAX, origin, at + ".clipped_samples");
        const json& acf = member(cj, "autocorrelation", origin, at);
        ch.acf_radius = (int)integer_value(member(acf, "radius", origin, at + ".autocorrelation"), 0, 64, origin,
                                           at + ".autocorrelation.radius");
        ch.autocorrelation =
            number_array(member(acf, "values", origin, at + ".autocorrelation"), origin, at + ".autocorrelation.values");
        p.channels.push_back(std::move(ch));
    }
    const json& corr = member(doc, "channel_correlation", origin, "");
    p.channel_correlation.clear();
    if (!corr.is_array() || corr.size() != p.channels.size())
        fail(origin, "channel_correlation", "expected one row per channel");
    for (size_t a = 0; a < corr.size(); ++a) {
        std::vector<double> row = number_array(corr[a], origin, "channel_correlation[" + std::to_string(a) + "]");
        if (row.size() != p.channels.size())
            fail(origin, "channel_correlation[" + std::to_string(a) + "]", "expected one value per channel");
        p.channel_correlation.insert(p.channel_correlation.end(), row.begin(), row.end());
    }
    if (doc.contains("analysis")) {
        const json& a = doc["analysis"];
        if (!a.is_object()) fail(origin, "analysis", "expected an object");
        if (a.contains("block_size_px"))
            p.block_size_px = (int)integer_value(a["block_size_px"], 0, INT_MAX, origin, "analysis.block_size_px");
        if (a.contains("blocks_used"))
            p.blocks_used = integer_value(a["blocks_used"], 0, LLONG_MAX, origin, "analysis.blocks_used");
        if (a.contains("sparse_levels")) {
            const json& sparse = a["sparse_levels"];
            if (!sparse.is_array()) fail(origin, "analysis.sparse_levels", "expected an array");
            for (size_t i = 0; i < sparse.size(); ++i) {
                const std::string at = "analysis.sparse_levels[" + std::to_string(i) + "]";
                SparseLevel level;
                level.channel = text_field(sparse[i], "channel", origin, at);
                level.level = finite_number(member(sparse[i], "level", origin, at), origin, at + ".level");
                level.samples =
                    integer_value(member(sparse[i], "samples", origin, at), 0, LLONG_MAX, origin, at + ".samples");
                if (sparse[i].contains("plate_samples"))
                    level.plate_samples =
                        integer_value(sparse[i]["plate_samples"], 0, LLONG_MAX, origin, at + ".plate_samples");
                p.sparse_levels.push_back(level);
            }
        }
    }
    validate_grain_profile(p, origin);
    return p;
}

GrainProfile load_grain_profile_file(const std::string& path) {
    return parse_grain_profile_json(read_json_file<GrainProfileError>(path, "grain profile"), path);
}

std::string grain_profile_to_json(const GrainProfile& p) {
    json doc = {{"format", "darkroom-grain-profile"},
                {"version", GrainProfile::kFormatVersion},
                {"colorspace", p.colorspace},
                {"encoding", encoding_name(p.encoding)},
                {"sources", p.sources}};
    json channels = json::array();
    for (const GrainChannel& ch : p.channels) {
        json response = {{"level", ch.level}, {"sigma", ch.sigma}};
        if (!ch.samples.empty()) response["samples"] = ch.samples;
        if (!ch.plate_samples.empty()) response["plate_samples"] = ch.plate_samples;
        if (!ch.sigma_error.empty()) response["relative_error"] = ch.sigma_error;
        channels.push_back({{"name", ch.name},
                            {"response", response},
                            {"clipped_samples", ch.clipped_samples},
                            {"autocorrelation", {{"radius", ch.acf_radius}, {"values", ch.autocorrelation}}},
                            {"derived",
                             {{"noise_equivalent_area_px2", noise_equivalent_area_px2(ch)},
                              {"half_power_cycles_per_px", half_power_frequency(radial_power_spectrum(ch))}}}});
    }
    doc["channels"] = channels;
    json corr = json::array();
    const size_t n = p.channels.size();
    for (size_t a = 0; a < n; ++a)
        corr.push_back(std::vector<double>(p.channel_correlation.begin() + a * n, p.channel_correlation.begin() + (a + 1) * n));
    doc["channel_correlation"] = corr;
    if (p.block_size_px > 0) {
        json sparse = json::array();
        for (const SparseLevel& s : p.sparse_levels)
            sparse.push_back(
                {{"channel", s.channel}, {"level", s.level}, {"samples", s.samples}, {"plate_samples", s.plate_samples}});
        doc["analysis"] = {{"block_size_px", p.block_size_px}, {"blocks_used", p.blocks_used}, {"sparse_levels", sparse}};
    }
    return doc.dump(1);
}

}  // namespace darkroom
