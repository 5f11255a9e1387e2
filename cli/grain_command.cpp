// darkroom grain analyze|apply|compare|predict: plate matching. Measures a scanned
// plate's grain per channel (core/plate/grain_analysis.h), puts grain with those
// statistics on clean images (grain_synthesis.h), checks how well two grains match
// (grain_compare.h), and predicts a profile from a stock and a scan (grain_prediction.h).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "cli/chart.h"
#include "cli/commands.h"
#include "cli/atomic_file.h"
#include "cli/batch.h"
#include "cli/image_io.h"
#include "look/render.h"
#include "core/plate/grain_analysis.h"
#include "core/plate/grain_compare.h"
#include "core/plate/grain_prediction.h"
#include "core/plate/grain_synthesis.h"
#include "core/plate/noise_spectrum.h"

namespace darkroom::cli {

namespace {

constexpr int kMismatchExitCode = 4;

std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower((unsigned char)c));
    return s;
}

bool ends_with(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

SignalEncoding parse_encoding(const std::string& name) {
    if (name == "linear") return SignalEncoding::linear;
    if (name == "log") return SignalEncoding::log;
    if (name == "display") return SignalEncoding::display;
    throw UserError("--encoding must be linear, log or display, not '" + name + "'");
}

// "1001-1010", "1001,1003,1005" or a mix.
std::vector<int> parse_frames(const std::string& text) {
    std::vector<int> frames;
    size_t start = 0;
    while (start <= text.size()) {
        size_t comma = text.find(',', start);
        std::string part = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        try {
            size_t dash = part.find('-', 1);
            size_t used = 0;
            int first = std::stoi(part, &used);
            int last = first;
            if (dash != std::string::npos) last = std::stoi(part.substr(dash + 1));
            else if (used != part.size()) throw std::invalid_argument(part);
            if (last < first || last - first > 100000) throw std::invalid_argument(part);
            for (int f = first; f <= last; ++f) frames.push_back(f);
        } catch (const std::exception&) {
            throw UserError("--frames: cannot read '" + part + "' (expected e.g. 1001-1010 or 1001,1005)");
        }
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return frames;
}

// A path with a frame pattern (#### or %04d) expanded for each frame; others unchanged.
std::vector<std::string> expand_frames(const std::vector<std::string>& plates, const std::string& frames_text) {
    std::vector<int> frames = frames_text.empty() ? std::vector<int>{} : parse_frames(frames_text);
    std::vector<std::string> out;
    for (const std::string& p : plates) {
        size_t hash = p.find('#'), percent = p.find('%');
        if (hash == std::string::npos && percent == std::string::npos) {
            out.push_back(p);
            continue;
        }
        if (frames.empty()) throw UserError("'" + p + "' has a frame pattern: give the frames with --frames");
        for (int f : frames) {
            if (hash != std::string::npos) {
                size_t run = p.find_first_not_of('#', hash) - hash;
                char number[32];
                std::snprintf(number, sizeof number, "%0*d", (int)run, f);
                out.push_back(p.substr(0, hash) + number + p.substr(hash + run));
            } else {
                char path[4096];
                std::snprintf(path, sizeof path, p.c_str(), f);
                out.push_back(path);
            }
        }
    }
    return out;
}

// Pixels in absolute frame coordinates (the file's data window), of `layer` (read_image);
// the rest of the file with them where `other_parts`.
LoadedImage read_plate(const std::string& path, const std::optional<std::string>& layer, bool other_parts = false) {
    LoadedImage in = read_image(path, layer, other_parts);
    const int w = in.pixels.window.width(), h = in.pixels.window.height();
    in.pixels.window = {in.spec.x, in.spec.y, in.spec.x + w, in.spec.y + h};
    return in;
}

// A file's encoding: as --iscolorspace names it, else as the file's own tag does (OpenImageIO
// tags a log DPX scan "KodakLog", a PNG "sRGB", an EXR "Linear"), else by the pixels' type.
SignalEncoding file_encoding(const std::string& colorspace_flag, const OIIO::ImageSpec& spec) {
    const SignalEncoding by_type = spec.format.is_floating_point() ? SignalEncoding::linear : SignalEncoding::display;
    return encoding_of_colorspace(colorspace_flag,
                                  encoding_of_colorspace(spec.get_string_attribute("oiio:ColorSpace"), by_type));
}

struct AnalyzeOptions {
    std::vector<std::string> plates;
    std::string output, colorspace, encoding, frames, plot;
    std::optional<std::string> layer;  // --layer
    std::vector<int> region;
    // The analysis' own defaults.
    int block_size = GrainAnalysisSettings{}.block_size_px, levels = GrainAnalysisSettings{}.level_bins,
        min_blocks = GrainAnalysisSettings{}.min_blocks_per_level, threads = 0;
};

GrainProfile analyze_files(const std::vector<std::string>& paths, const AnalyzeOptions& o, const std::vector<int>& region,
                           const std::string& region_flag) {
    std::vector<LoadedImage> images;
    std::vector<ConstImageView> views;
    GrainAnalysisSettings settings;
    settings.block_size_px = o.block_size;
    settings.level_bins = o.levels;
    settings.min_blocks_per_level = o.min_blocks;
    settings.threads = o.threads;
    settings.colorspace = o.colorspace;
    for (const std::string& p : paths) images.push_back(read_plate(p, o.layer));
    const OIIO::ImageSpec& first = images.front().spec;
    // The colour channels only (as develop reads them): alpha and depth carry no grain.
    settings.channels = colour_channel_count(first);
    for (int c = 0; c < settings.channels && c < (int)first.channelnames.size(); ++c)
        settings.channel_names.push_back(first.channelnames[c]);
    settings.encoding = !o.encoding.empty() ? parse_encoding(o.encoding) : file_encoding(o.colorspace, first);
    for (size_t i = 0; i < images.size(); ++i) {
        if (images[i].pixels.channels < settings.channels)
            throw UserError("'" + paths[i] + "' has " + std::to_string(images[i].pixels.channels) + " channels, '" +
                            paths[0] + "' " + std::to_string(settings.channels));
        ConstImageView view = images[i].pixels.view();
        Window w = window_flag(region, view.window, region_flag);
        view.data = view.at(w.x0, w.y0);
        view.window = w;
        views.push_back(view);
    }
    try {
        GrainProfile profile = analyze_grain(views, settings);
        profile.sources = paths;
        return profile;
    } catch (const GrainAnalysisError& e) {
        throw UserError(std::string(paths.size() == 1 ? "'" + paths[0] + "'" : "the plates") + ": " + e.what());
    }
}

// A profile file (.json) as it is, or an image analysed.
GrainProfile profile_of(const std::string& path, const AnalyzeOptions& o, const std::vector<int>& region,
                        const std::string& region_flag) {
    if (ends_with(lower(path), ".json")) {
        try {
            return load_grain_profile_file(path);
        } catch (const GrainProfileError& e) {
            throw UserError(e.what());
        }
    }
    return analyze_files({path}, o, region, region_flag);
}

Chart response_chart(const std::string& title, const std::vector<std::pair<std::string, const GrainProfile*>>& profiles) {
    Chart chart;
    chart.title = title;
    chart.x.label = "signal level (" + std::string(encoding_name(profiles.front().second->encoding)) + ")";
    chart.y.label = "grain standard deviation";
    for (size_t k = 0; k < profiles.size(); ++k)
        for (size_t c = 0; c < profiles[k].second->channels.size(); ++c) {
            const GrainChannel& ch = profiles[k].second->channels[c];
            ChartSeries s{ch.name + profiles[k].first, ch.level, ch.sigma, channel_colour(ch.name, (int)c), k > 0};
            chart.series.push_back(s);
        }
    return chart;
}

Chart spectrum_chart(const std::vector<std::pair<std::string, const GrainProfile*>>& profiles) {
    Chart chart;
    chart.title = "Noise power spectrum (radial, normalised)";
    chart.x.label = "cycles per pixel";
    chart.y.label = "NPS (px^2)";
    chart.y.log = true;
    for (size_t k = 0; k < profiles.size(); ++k)
        for (size_t c = 0; c < profiles[k].second->channels.size(); ++c) {
            const GrainChannel& ch = profiles[k].second->channels[c];
            RadialSpectrum nps = radial_power_spectrum(ch);
            chart.series.push_back(
                {ch.name + profiles[k].first, nps.cycles_per_px, nps.power, channel_colour(ch.name, (int)c), k > 0});
        }
    return chart;
}

void plot(const std::string& path, const std::vector<Chart>& charts) {
    bool text = true;
    write_charts(path, charts, &text);
    if (!text) std::cerr << "darkroom: warning: no font for OpenImageIO's text: '" << path << "' has no labels\n";
}

void print_profile(const GrainProfile& p) {
    std::printf("encoding %s%s%s", encoding_name(p.encoding), p.colorspace.empty() ? "" : ", colour space ",
                p.colorspace.c_str());
    if (p.block_size_px > 0)
        std::printf(", %d px blocks, %lld grain-only blocks in every channel", p.block_size_px, p.blocks_used);
    std::printf("\n");
    for (const GrainChannel& ch : p.channels) {
        double lo = *std::min_element(ch.sigma.begin(), ch.sigma.end());
        double hi = *std::max_element(ch.sigma.begin(), ch.sigma.end());
        long long samples = 0;
        for (long long s : ch.samples) samples += s;
        std::printf("  %-3s %2zu levels %.4g..%.4g, sigma %.4g..%.4g", ch.name.c_str(), ch.level.size(), ch.level.front(),
                    ch.level.back(), lo, hi);
        if (!ch.sigma_error.empty())
            std::printf(" (within %.1f %%)", 100 * *std::max_element(ch.sigma_error.begin(), ch.sigma_error.end()));
        std::printf(", %lld px", samples);
        if (ch.clipped_samples > 0) std::printf(" (%lld px left out as clipped)", ch.clipped_samples);
        std::printf("; half-power %.3f cycles/px, noise-equivalent area %.2f px^2\n",
                    half_power_frequency(radial_power_spectrum(ch)), noise_equivalent_area_px2(ch));
    }
    const size_t n = p.channels.size();
    std::printf("  channel correlation:");
    for (size_t a = 0; a < n; ++a)
        for (size_t b = a + 1; b < n; ++b)
            std::printf(" %s-%s %.3f", p.channels[a].name.c_str(), p.channels[b].name.c_str(), p.correlation((int)a, (int)b));
    std::printf("\n");
    if (!p.sparse_levels.empty()) {
        std::string per_channel;
        for (const GrainChannel& ch : p.channels) {
            const long long left_out = std::count_if(p.sparse_levels.begin(), p.sparse_levels.end(),
                                                     [&](const SparseLevel& s) { return s.channel == ch.name; });
            if (left_out > 0) per_channel += " " + ch.name + " " + std::to_string(left_out);
        }
        std::printf("  levels left out (too few grain-only blocks, or picture content in all):%s\n", per_channel.c_str());
    }
    if (p.block_size_px > 0) {
        const ProfileAssessment trust = assess_grain_profile(p);
        std::printf("profile: %s (%s)\n", quality_name(trust.quality), trust.reason.c_str());
    }
}

void run_analyze(const AnalyzeOptions& o) {
    GrainProfile profile = analyze_files(expand_frames(o.plates, o.frames), o, o.region, "--region");
    write_text_atomically(o.output, grain_profile_to_json(profile) + "\n");
    print_profile(profile);
    if (assess_grain_profile(profile).quality == ProfileQuality::unreliable)
        std::cerr << "darkroom: warning: the grain profile is unreliable: check it against the plate (grain compare) or "
                     "analyse more frames or a region with flat areas\n";
    if (!o.plot.empty()) plot(o.plot, {response_chart("Grain response", {{"", &profile}}), spectrum_chart({{"", &profile}})});
}

struct ApplyOptions {
    BatchOptions batch;
    std::string profile, colorspace;
    std::vector<double> gain{1.0}, size{1.0};
    double tilt = 0;
    uint64_t seed = 0;
    int frame = 0, threads = 0;
    std::optional<std::string> layer;  // --layer
};

// Puts the grain on one frame; returns how to write it.
FrameWrite apply_frame(const ApplyOptions& o, const GrainSynthesisPlan& grain, const FrameJob& job, int threads,
                       FrameReport& report, Progress& progress) {
    auto start = std::chrono::steady_clock::now();
    LoadedImage in = read_plate(job.input, o.layer, true);
    check_output_holds_parts(job, in, report, progress);
    report.read_seconds = seconds_since(start);
    // Grain levels are code values of the profile's encoding: another encoding's pixels would
    // get grain of the wrong amount at the wrong levels.
    const GrainProfile& profile = grain.profile;
    if (const SignalEncoding input = file_encoding(o.colorspace, in.spec); input != profile.encoding) {
        const std::string tag = in.spec.get_string_attribute("oiio:ColorSpace");
        throw UserError("'" + job.input + "' is " + encoding_name(input) + " (" +
                        (!o.colorspace.empty() ? "--iscolorspace " + o.colorspace
                         : tag.empty()         ? std::string("its pixel type")
                                               : "its colour-space tag " + tag) +
                        "), the grain profile '" + o.profile + "' was measured in " + encoding_name(profile.encoding) +
                        (profile.colorspace.empty() ? "" : " (" + profile.colorspace + ")") + ": convert the input to " +
                        (profile.colorspace.empty() ? encoding_name(profile.encoding) : profile.colorspace) +
                        " first, or give its colour space with --iscolorspace if the file says wrong");
    }
    start = std::chrono::steady_clock::now();
    ImageView view = in.pixels.view();
    view.colour_channels = colour_channel_count(in.spec);
    apply_plate_grain_to_element(grain, o.profile, view, premultiplied_alpha_channel(in.spec), o.seed, job.frame, threads);
    report.develop_seconds = seconds_since(start);
    const WriteOptions write = with_input_data_type(o.batch.write, in.spec, job.output);
    return [in = std::move(in), output = job.output, protected_input = o.batch.run.in_place ? "" : job.input, write] {
        return write_image_to_temp(output, in.pixels, in.spec, protected_input, write, in.through);
    };
}

void run_apply(ApplyOptions& o, const CLI::App& cmd) {
    // One value for every channel, or one each.
    auto per_channel = [](const std::vector<double>& v) {
        return std::array<double, 3>{v[0], v[std::min<size_t>(1, v.size() - 1)], v[std::min<size_t>(2, v.size() - 1)]};
    };
    const GrainSynthesisPlan grain = read_plate_grain(o.profile, GrainControls{per_channel(o.gain), per_channel(o.size), o.tilt});
    const std::string& measured_in = grain.profile.colorspace;
    if (!o.colorspace.empty() && !measured_in.empty() && lower(o.colorspace) != lower(measured_in))
        throw UserError("'" + o.profile + "' was measured in " + measured_in + ", the input is " + o.colorspace +
                        ": convert the input to " + measured_in + " first (grain levels are in its encoding)");
    run_batch(o.batch, o.frame, cmd.get_option("--frame")->count() > 0, o.threads, false, [&](int) -> FrameWork {
        return [&](const FrameJob& job, int threads, bool, FrameReport& report, Progress& progress) {
            return apply_frame(o, grain, job, threads, report, progress);
        };
    }, [&](const FrameJob& job, FrameReport&, Progress&) {
        require_holds_parts(job.output, job.input, read_image_header(job.input, o.layer));
    });
}

struct CompareOptions {
    std::string a, b, plot;
    bool json = false;
    std::vector<int> region_a, region_b;
    GrainMatchTolerance tolerance;
    AnalyzeOptions analysis;
};

void run_compare(const CompareOptions& o) {
    GrainProfile a = profile_of(o.a, o.analysis, o.region_a, "--region-a");
    GrainProfile b = profile_of(o.b, o.analysis, o.region_b, "--region-b");
    GrainMatch match;
    try {
        match = compare_grain_profiles(a, b);
    } catch (const GrainProfileError& e) {
        throw UserError(e.what());
    }
    const bool passes = match.passes(o.tolerance);
    std::printf("%-8s %-22s %-16s %-26s\n", "channel", "response error", "NPS distance", "half-power (A, B)");
    for (const ChannelMatch& c : match.channels)
        std::printf("%-8s %6.2f %% (%2d levels)   %6.3f dB        %.3f, %.3f cycles/px\n", c.name.c_str(),
                    c.response_error_percent, c.levels_compared, c.nps_distance_db, c.half_power_a, c.half_power_b);
    std::printf("largest channel correlation difference: %.3f\n", match.max_correlation_difference);
    std::printf("%s (tolerances: response %.3g %%, NPS %.3g dB, correlation %.3g)\n",
                passes ? "grain matches" : "grain does not match", o.tolerance.response_percent, o.tolerance.nps_db,
                o.tolerance.correlation);
    if (!o.plot.empty())
        plot(o.plot, {response_chart("Grain response: A solid, B dashed", {{" A", &a}, {" B", &b}}),
                      spectrum_chart({{" A", &a}, {" B", &b}})});
    std::fflush(stdout);
    if (!passes) std::exit(kMismatchExitCode);
}

struct PredictOptions {
    std::string stock, output;
    int width_px = 0;
    double frame_width_mm = 0;
    // The scan's balance, as the look's scan settings (look/parameters.cpp) spell them.
    std::string scan_balance = parameter("scan-balance").default_value().get<std::string>();
    double scan_aim = parameter("scan-aim").default_value().get<double>();
};

void run_predict(const PredictOptions& o) {
    Stock stock;
    try {
        stock = find_stock(o.stock);
    } catch (const StockError& e) {
        throw UserError(e.what());
    }
    Look scan;
    for (const auto& [key, value] : {std::pair<std::string, nlohmann::json>{"scan-balance", o.scan_balance},
                                     {"scan-aim", o.scan_aim}})
        try {
            set_value(scan, parameter(key), value);
        } catch (const UserError& e) {
            throw UserError("--" + key + " " + e.what());
        }
    const ScanGeometry geometry{o.width_px, o.frame_width_mm, scan.settings.scan_balance, scan.settings.scan_aim_code};
    GrainProfile profile = predict_grain_profile(stock, geometry);
    write_text_atomically(o.output, grain_profile_to_json(profile) + "\n");
    std::printf("%s\n", profile.sources.front().c_str());
    print_profile(profile);
}

void add_analysis_flags(CLI::App& cmd, AnalyzeOptions& o) {
    cmd.add_option("--iscolorspace", o.colorspace, "The plate's colour space (recorded; implies the encoding)");
    cmd.add_option("--encoding", o.encoding, "linear, log or display (default: from --iscolorspace, else display for "
                                             "integer files and linear for float files)");
    cmd.add_option("--block-size", o.block_size, "Block size in pixels (default: from the grain, 16 to 64)")
        ->check(CLI::Range(8, 256));
    cmd.add_option("--levels", o.levels, "Signal level bins of the response curve")
        ->check(CLI::Range(1, 256))
        ->capture_default_str();
    cmd.add_option("--min-blocks", o.min_blocks, "Grain-only blocks a level needs to be estimated")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    cmd.add_option("--threads", o.threads, "Worker threads, 0 = all cores");
    add_layer_flag(cmd, o.layer, "measure");
}

}  // namespace

void add_grain_command(CLI::App& app) {
    CLI::App* grain = app.add_subcommand("grain", "Plate matching: measure a plate's grain and put it on CG elements");
    grain->require_subcommand(1);

    auto a = std::make_shared<AnalyzeOptions>();
    CLI::App* analyze = grain->add_subcommand("analyze", "Estimate a plate's grain per channel into a profile");
    analyze->add_option("plates", a->plates, "Plate frames (a path with #### or %04d takes --frames)")->required();
    analyze->add_option("-o,--out", a->output, "Grain profile (.json)")->required();
    analyze->add_option("--region", a->region, "Analyse only this region X,Y,W,H")->delimiter(',')->expected(4);
    analyze->add_option("--frames", a->frames, "Frames for a pattern path: 1001-1010 or 1001,1005");
    analyze->add_option("--plot", a->plot, "Chart of the response and the NPS (.png or .svg)");
    add_analysis_flags(*analyze, *a);
    analyze->callback([a] { run_analyze(*a); });

    auto p = std::make_shared<ApplyOptions>();
    CLI::App* apply = grain->add_subcommand(
        "apply", "Add grain with a profile's statistics to a clean image or sequence (each frame its own grain)");
    add_batch_flags(*apply, p->batch, "Clean image or sequence, in the encoding of the profile",
                    "Output image or sequence");
    apply->get_option("input")->required();
    apply->get_option("-o")->required();
    apply->add_option("--profile", p->profile, "Grain profile (.json)")->required();
    apply->add_option("--seed", p->seed, "Grain seed");
    apply->add_option("--frame", p->frame, "Frame number of a single image (the grain changes with it; a sequence's "
                                           "frames use their own)");
    apply->add_option("--iscolorspace", p->colorspace, "The input's colour space (must be the profile's)");
    apply->add_option("--gain", p->gain, "Multiplies the profile's sigma: one value, or R,G,B")
        ->delimiter(',')
        ->expected(1, 3)
        ->check(CLI::Range(0.0, kMaxGrainScale));
    apply->add_option("--size", p->size, "Multiplies the profile's grain size: one value, or R,G,B")
        ->delimiter(',')
        ->expected(1, 3)
        ->check(CLI::Range(kMinGrainSizeScale, kMaxGrainSizeScale));
    apply->add_option("--tilt", p->tilt, "Tilts the response: stops more sigma at the profile's highest level than at "
                                         "its lowest")
        ->check(CLI::Range(-kMaxResponseTilt, kMaxResponseTilt));
    apply->add_option("--threads", p->threads, "Worker threads, 0 = all cores; the result does not depend on it");
    add_layer_flag(*apply, p->layer, "put the grain on");
    apply->callback([p, apply] { run_apply(*p, *apply); });

    auto c = std::make_shared<CompareOptions>();
    CLI::App* compare = grain->add_subcommand(
        "compare", "How well the grain of two images (or profiles) matches; exit 4 when outside the tolerances");
    compare->add_option("a", c->a, "Image or grain profile (.json)")->required();
    compare->add_option("b", c->b, "Image or grain profile (.json)")->required();
    compare->add_option("--region-a", c->region_a, "Region X,Y,W,H of A")->delimiter(',')->expected(4);
    compare->add_option("--region-b", c->region_b, "Region X,Y,W,H of B")->delimiter(',')->expected(4);
    compare->add_option("--plot", c->plot, "Chart of both responses and spectra side by side (.png or .svg)");
    compare->add_option("--max-response-error", c->tolerance.response_percent, "Tolerance, percent");
    compare->add_option("--max-nps-distance", c->tolerance.nps_db, "Tolerance, dB");
    compare->add_option("--max-correlation-difference", c->tolerance.correlation, "Tolerance");
    add_analysis_flags(*compare, c->analysis);
    compare->callback([c] { run_compare(*c); });

    auto d = std::make_shared<PredictOptions>();
    CLI::App* predict = grain->add_subcommand("predict", "Predict a profile from a stock scanned at a resolution");
    predict->add_option("--stock", d->stock, "Built-in stock id or stock file")->required();
    predict->add_option("--width", d->width_px, "Scan width in pixels (e.g. 4096)")->required()->check(CLI::Range(1, 1 << 20));
    predict->add_option("--frame-width-mm", d->frame_width_mm, "Scanned frame width (default: the stock's format)")
        ->check(CLI::PositiveNumber);
    predict->add_option("--scan-balance", d->scan_balance, parameter("scan-balance").help)->capture_default_str();
    predict->add_option("--scan-aim", d->scan_aim, parameter("scan-aim").help)->capture_default_str();
    predict->add_option("-o,--out", d->output, "Grain profile (.json)")->required();
    predict->callback([d] { run_predict(*d); });
}

}  // namespace darkroom::cli
