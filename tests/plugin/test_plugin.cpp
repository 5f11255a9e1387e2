// The OpenFX bundle, loaded by a test host exactly as a compositing host loads it.
#include <chrono>
#include <OpenImageIO/imagebuf.h>
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <algorithm>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "look/parameters.h"
#include "tests/ocio/ocio_variable.h"
#include "tests/plugin/test_host.h"

namespace fs = std::filesystem;
using namespace testhost;

namespace {

const fs::path kTmp = DARKROOM_TEST_TMP;

// The plugin falls back to $OCIO when its config parameter is empty, as the CLI does; the
// tests compare with the embedded config, so neither may see a user's $OCIO.
const bool kNoUserOcio = [] { return unsetenv("OCIO") == 0; }();

std::string run(const std::string& command) {
    std::string text;
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    REQUIRE(pipe);
    char buf[512];
    while (std::fgets(buf, sizeof buf, pipe)) text += buf;
    pclose(pipe);
    return text;
}

// A scene with smooth gradients and hard edges (so scattering and grain both show), top-down.
std::vector<float> scene(int w, int h, int channels) {
    std::vector<float> px((size_t)w * h * channels);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float* p = &px[((size_t)y * w + x) * channels];
            bool square = x > w / 3 && x < 2 * w / 3 && y > h / 3 && y < 2 * h / 3;
            p[0] = square ? 2.0f : 0.02f + 0.5f * x / w;
            p[1] = square ? 1.5f : 0.05f + 0.4f * y / h;
            p[2] = square ? 0.8f : 0.1f;
            if (channels == 4) p[3] = 0.25f + 0.75f * (float)(x + y) / (w + h);
        }
    return px;
}

std::string write_exr(const std::string& name, const std::vector<float>& px, int w, int h, int channels) {
    fs::create_directories(kTmp);
    std::string path = (kTmp / name).string();
    OIIO::ImageBuf buf(OIIO::ImageSpec(w, h, channels, OIIO::TypeDesc::FLOAT), const_cast<float*>(px.data()));
    REQUIRE(buf.write(path));
    return path;
}

std::vector<float> read_exr(const std::string& path) {
    OIIO::ImageBuf buf(path);
    REQUIRE(buf.read(0, 0, true, OIIO::TypeDesc::FLOAT));
    std::vector<float> out(buf.spec().image_pixels() * buf.nchannels());
    buf.get_pixels(buf.roi(), OIIO::TypeDesc::FLOAT, out.data());
    return out;
}

// `darkroom develop` on `input`, its output's pixels.
std::vector<float> develop(const std::string& input, const std::string& flags) {
    std::string out = (kTmp / ("cli-" + std::to_string(std::hash<std::string>{}(input + flags)) + ".exr")).string();
    fs::remove(out);
    std::string log = run(std::string(DARKROOM_EXE) + " develop " + input + " -o " + out + " " + flags);
    INFO(log);
    REQUIRE(fs::exists(out));
    return read_exr(out);
}

std::unique_ptr<Instance> make_instance() {
    REQUIRE(kNoUserOcio);
    auto inst = Plugin::get().create_instance();
    REQUIRE(inst->create_status() == kOfxStatOK);
    return inst;
}

// The settings the CLI comparisons use: a small physical frame so that scattering and grain
// span several pixels of a small test image.
void set_common_look(Instance& inst) {
    inst.set_int("film", inst.choice_index("film", "Tri-X"));
    inst.set_int("paper", inst.choice_index("paper", "grade 2"));
    inst.set_int("seed", 5);
    inst.set_double("frameWidthMm", 4);
    inst.set_double("printWidthMm", 30);
    inst.set_double("exposure", 0.5);
    inst.set_double("printExposure", -0.3);
}
const std::string kCommonFlags =
    "--film kodak-tri-x-400 --paper vdr-paper-grade-2 --seed 5 --frame-width-mm 4 --print-width-mm 30 "
    "--exposure 0.5 --print-exposure -0.3";

bool same_bits(const Frame& a, const Frame& b) {
    return a.pixels.size() == b.pixels.size() &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0;
}

long count_value(const Frame& f, float v) {
    long n = 0;
    for (float p : f.pixels) n += p == v;
    return n;
}

}  // namespace

TEST_CASE("the bundle exports only the OpenFX entry points and needs no OpenImageIO", "[plugin]") {
    std::string symbols = run("nm -D --defined-only " DARKROOM_OFX_BUNDLE);
    std::set<std::string> names;
    std::istringstream lines(symbols);
    for (std::string line; std::getline(lines, line);)
        if (!line.empty()) names.insert(line.substr(line.rfind(' ') + 1));
    INFO(symbols);
    CHECK(names == std::set<std::string>{"OfxGetPlugin", "OfxGetNumberOfPlugins"});
    std::string libraries = run("ldd " DARKROOM_OFX_BUNDLE);
    INFO(libraries);
    CHECK(libraries.find("OpenImageIO") == std::string::npos);
    CHECK(libraries.find("not found") == std::string::npos);
}

TEST_CASE("describe declares the contexts, depths, clips and parameters", "[plugin]") {
    Plugin& plugin = Plugin::get();
    CHECK(std::string(plugin.ofx()->pluginApi) == kOfxImageEffectPluginApi);
    const PropertySet& p = plugin.descriptor().props;
    const auto& contexts = p.props.at(kOfxImageEffectPropSupportedContexts).s;
    CHECK(std::count(contexts.begin(), contexts.end(), kOfxImageEffectContextFilter) == 1);
    CHECK(std::count(contexts.begin(), contexts.end(), kOfxImageEffectContextGeneral) == 1);
    const auto& depths = p.props.at(kOfxImageEffectPropSupportedPixelDepths).s;
    CHECK(std::count(depths.begin(), depths.end(), kOfxBitDepthFloat) == 1);
    CHECK(p.get_string(kOfxImageEffectPluginRenderThreadSafety) == kOfxImageEffectRenderFullySafe);
    CHECK(p.get_int(kOfxImageEffectPropSupportsTiles) == 1);
    CHECK(p.get_int(kOfxImageEffectPropSupportsMultiResolution) == 1);

    Effect& ctx = plugin.context_descriptor();
    REQUIRE(ctx.clips.count("Source") == 1);
    REQUIRE(ctx.clips.count("Output") == 1);
    const auto& components = ctx.clips["Source"]->props.props.at(kOfxImageEffectPropSupportedComponents).s;
    CHECK(components == std::vector<std::string>{kOfxImageComponentRGBA, kOfxImageComponentRGB});
    for (const char* name : {"film", "filmFile", "paper", "paperFile", "output", "exposure", "printExposure",
                             "printerLights", "filtration", "grain", "grainAmount", "grainSize", "grainResponse",
                             "seed", "staticGrain", "halation", "mtf", "frameWidthMm", "printWidthMm", "ocioConfig",
                             "inputColorspace", "outputColorspace", "filmStock", "paperStock", "filmFrame"}) {
        INFO(name);
        Param* param = ctx.params.find(name);
        REQUIRE(param);
        // Every parameter sits in a labelled group.
        CHECK(ctx.params.find(param->props.get_string(kOfxParamPropParent)) != nullptr);
    }
    CHECK(ctx.params.find("exposure")->props.get_int(kOfxParamPropAnimates) == 1);
    CHECK(ctx.params.find("film")->props.get_int(kOfxParamPropAnimates) == 0);
    const auto& outputs = ctx.params.find("output")->props.props.at(kOfxParamPropChoiceOption).s;
    CHECK(outputs == std::vector<std::string>{"Print", "Negative", "Density", "Scan", "Texture"});

    // The general context has the same clips and parameters.
    Effect general;
    general.props = plugin.descriptor().props;
    PropertySet in;
    in.set(kOfxImageEffectPropContext, std::string(kOfxImageEffectContextGeneral));
    REQUIRE(plugin.call(kOfxImageEffectActionDescribeInContext, &general, &in, nullptr) == kOfxStatOK);
    CHECK(general.clips.size() == 2);
    CHECK(general.params.params.size() == ctx.params.params.size());
}

TEST_CASE("a full frame equals darkroom develop with the same settings", "[plugin][cli]") {
    const int w = 64, h = 48;
    std::vector<float> px = scene(w, h, 3);
    std::string input = write_exr("plugin-scene.exr", px, w, h, 3);
    auto inst = make_instance();
    set_common_look(*inst);
    inst->set_source(Frame::from_top_down(px, w, h, 3), kOfxImageOpaque);

    std::string output = GENERATE(as<std::string>{}, "print", "negative", "density");
    INFO("output " << output);
    inst->set_int("output", inst->choice_index("output", output == "print" ? "Print" : output == "negative" ? "Negative" : "Density"));
    RenderResult r = inst->render(12, {0, 0, w, h});
    INFO(inst->effect().persistent_message);
    REQUIRE(r.status == kOfxStatOK);
    REQUIRE(r.output.channels == 3);
    std::vector<float> cli = develop(input, kCommonFlags + " --frame 12 --output " + output);
    std::vector<float> ofx = r.output.to_top_down();
    REQUIRE(ofx.size() == cli.size());
    long differing = 0;
    for (size_t i = 0; i < cli.size(); ++i) differing += ofx[i] != cli[i];
    CHECK(differing == 0);
}

TEST_CASE("tiles equal the full frame bit for bit, whatever the thread count", "[plugin][determinism]") {
    const int w = 80, h = 70;
    auto inst = make_instance();
    set_common_look(*inst);
    inst->set_source(Frame::from_top_down(scene(w, h, 4), w, h, 4));
    set_cpu_count(1);
    RenderResult full = inst->render(7, {0, 0, w, h});
    REQUIRE(full.status == kOfxStatOK);
    CHECK(count_value(full.output, -7.0f) == 0);
    // Three row bands of the full frame on the host's threads.
    set_cpu_count(4);
    RenderResult threaded = inst->render(7, {0, 0, w, h});
    REQUIRE(threaded.status == kOfxStatOK);
    CHECK(same_bits(full.output, threaded.output));
    set_cpu_count(3);
    RenderResult tiles = inst->render_tiles(7, {0, 0, w, h}, 23, 17);
    REQUIRE(tiles.status == kOfxStatOK);
    CHECK(same_bits(full.output, tiles.output));
    set_cpu_count(4);
    CHECK(outstanding_allocations() == 0);
    CHECK(outstanding_images() == 0);
}

TEST_CASE("a frame whose region of definition is not at the origin develops the same pixels", "[plugin]") {
    const int w = 40, h = 30;
    Frame at_origin = Frame::from_top_down(scene(w, h, 4), w, h, 4), moved = at_origin;
    moved.bounds = {-13, 21, w - 13, h + 21};
    auto inst = make_instance();
    set_common_look(*inst);
    inst->set_source(at_origin);
    RenderResult a = inst->render(5, at_origin.bounds);
    inst->set_source(moved);
    RenderResult b = inst->render_tiles(5, moved.bounds, 16, 12);
    REQUIRE(a.status == kOfxStatOK);
    REQUIRE(b.status == kOfxStatOK);
    CHECK(same_bits(a.output, b.output));
}

TEST_CASE("a Source that is part of the project's format (a bounding box, overscan) develops as that part of the frame",
          "[plugin][determinism]") {
    // The film frame is the project's format: a Source whose region of definition is a CG
    // element's bounding box, or overscan, gets the frame's pixel pitch and grain, so away
    // from its edges (where filters clamp) its pixels are those of the whole frame.
    const int w = 96, h = 64;
    const Frame whole = Frame::from_top_down(scene(w, h, 4), w, h, 4);
    auto inst = make_instance();
    set_common_look(*inst);
    inst->set_double("halation", 0);
    inst->set_project({0, 0, (double)w, (double)h});
    inst->set_source(whole);
    RenderResult expected = inst->render(2, whole.bounds);
    REQUIRE(expected.status == kOfxStatOK);
    struct Part {
        OfxRectI bounds, compare;  // OFX pixels; compare: 10 or more from the part's edges, inside the frame
    };
    for (const Part& part : {Part{{24, 16, 72, 48}, {34, 26, 62, 38}}, Part{{-8, -6, 104, 70}, {10, 10, 86, 54}}}) {
        Frame source;
        source.bounds = part.bounds;
        source.channels = 4;
        source.pixels.resize(size_t(source.width()) * source.height() * 4);
        for (int y = part.bounds.y1; y < part.bounds.y2; ++y)
            for (int x = part.bounds.x1; x < part.bounds.x2; ++x)
                std::copy_n(whole.at(std::clamp(x, 0, w - 1), std::clamp(y, 0, h - 1)), 4, source.at(x, y));
        inst->set_source(source);
        RenderResult got = inst->render_tiles(2, part.bounds, 40, 24);
        INFO(inst->effect().persistent_message);
        REQUIRE(got.status == kOfxStatOK);
        for (int y = part.compare.y1; y < part.compare.y2; ++y)
            for (int x = part.compare.x1; x < part.compare.x2; ++x)
                for (int c = 0; c < 4; ++c) REQUIRE(got.output.at(x, y)[c] == expected.output.at(x, y)[c]);
    }
}

TEST_CASE("Film frame 'Source image' develops a plate whose format differs from the project's as its own frame",
          "[plugin]") {
    // A 64x48 plate in a 128x96 project: with the project's format as the film frame the plate
    // is half the frame (twice the pitch); as its own frame it develops as a host without a
    // project format develops it.
    const int w = 64, h = 48;
    const Frame plate = Frame::from_top_down(scene(w, h, 4), w, h, 4);
    auto own = make_instance(), project = make_instance(), no_project = make_instance();
    for (auto* inst : {own.get(), project.get(), no_project.get()}) {
        set_common_look(*inst);
        inst->set_source(plate);
    }
    own->set_project({0, 0, 128, 96});
    project->set_project({0, 0, 128, 96});
    own->set_int("filmFrame", own->choice_index("filmFrame", "Source image"));
    RenderResult expected = no_project->render(4, plate.bounds);
    RenderResult got = own->render_tiles(4, plate.bounds, 40, 24);
    INFO(own->effect().persistent_message);
    REQUIRE(got.status == kOfxStatOK);
    CHECK(same_bits(got.output, expected.output));
    CHECK_FALSE(same_bits(project->render(4, plate.bounds).output, expected.output));
}

TEST_CASE("render scale 0.5 renders the half-resolution frame with the same physical sizes", "[plugin][cli]") {
    const int w = 96, h = 64;
    std::vector<float> half = scene(w / 2, h / 2, 3);
    std::string input = write_exr("plugin-half.exr", half, w / 2, h / 2, 3);
    auto inst = make_instance();
    set_common_look(*inst);
    inst->set_source(Frame::from_top_down(half, w / 2, h / 2, 3), kOfxImageOpaque);
    inst->set_source_rod({0, 0, (double)w, (double)h});  // canonical: the full-resolution frame

    RenderResult r = inst->render(3, {0, 0, w / 2, h / 2}, 0.5);
    INFO(inst->effect().persistent_message);
    REQUIRE(r.status == kOfxStatOK);
    // The frame width in mm is the same, so the pixel pitch doubles: exactly what the CLI
    // does with the half-size image and the same --frame-width-mm; and a proxy render at the
    // default Quality (fast) is a preview.
    std::vector<float> cli = develop(input, kCommonFlags + " --frame 3 --quality preview");
    std::vector<float> ofx = r.output.to_top_down();
    REQUIRE(ofx.size() == cli.size());
    CHECK(std::memcmp(ofx.data(), cli.data(), cli.size() * sizeof(float)) == 0);

    // Tiles at scale 0.5 agree with the full frame at scale 0.5.
    RenderResult tiles = inst->render_tiles(3, {0, 0, w / 2, h / 2}, 13, 11, 0.5);
    REQUIRE(tiles.status == kOfxStatOK);
    CHECK(same_bits(r.output, tiles.output));

    // The region of interest is in canonical coordinates: a region at the frame's centre
    // grows by the same halo in pixels, i.e. twice as many canonical units at scale 0.5.
    OfxRectD region{40, 30, 50, 34}, roi_full{}, roi_half{};
    REQUIRE(inst->region_of_interest(3, region, 1.0, &roi_full) == kOfxStatOK);
    REQUIRE(inst->region_of_interest(3, region, 0.5, &roi_half) == kOfxStatOK);
    CHECK(roi_full.x1 < region.x1);
    CHECK(roi_full.x2 > region.x2);
    CHECK(roi_half.x1 >= 0);
    CHECK(roi_half.y2 <= h);
}

TEST_CASE("premultiplied input is unpremultiplied, developed and premultiplied again, and alpha passes through",
          "[plugin]") {
    const int w = 40, h = 30;
    std::vector<float> straight = scene(w, h, 4), premultiplied = straight;
    for (size_t i = 0; i < premultiplied.size(); i += 4)
        for (int c = 0; c < 3; ++c) premultiplied[i + c] *= premultiplied[i + 3];
    auto inst = make_instance();
    set_common_look(*inst);
    inst->set_source(Frame::from_top_down(straight, w, h, 4), kOfxImageUnPreMultiplied);
    RenderResult u = inst->render(1, {0, 0, w, h});
    inst->set_source(Frame::from_top_down(premultiplied, w, h, 4), kOfxImagePreMultiplied);
    RenderResult p = inst->render(1, {0, 0, w, h});
    REQUIRE(u.status == kOfxStatOK);
    REQUIRE(p.status == kOfxStatOK);
    const Frame input = Frame::from_top_down(straight, w, h, 4);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float *a = u.output.at(x, y), *b = p.output.at(x, y), *in = input.at(x, y);
            REQUIRE(b[3] == in[3]);
            REQUIRE(a[3] == in[3]);
            // Unpremultiplying (c a) / a can differ from c in the last bit, hence the tolerance.
            for (int c = 0; c < 3; ++c) REQUIRE(b[c] == Approx(a[c] * a[3]).epsilon(1e-4).margin(1e-7));
        }
    // darkroom develop reads an RGBA EXR as premultiplied (OpenImageIO's convention) and gives
    // the same pixels, bit for bit.
    const std::vector<float> cli = develop(write_exr("plugin-premultiplied.exr", premultiplied, w, h, 4), kCommonFlags + " --frame 1");
    const std::vector<float> ofx = p.output.to_top_down();
    REQUIRE(cli.size() == ofx.size());
    long differing = 0;
    for (size_t i = 0; i < cli.size(); ++i) differing += ofx[i] != cli[i];
    CHECK(differing == 0);
}

TEST_CASE("16-bit and 8-bit images render as the float image does, to their precision", "[plugin]") {
    const int w = 40, h = 30;
    auto inst = make_instance();
    set_common_look(*inst);
    // A print's reflectance lies in 0-1, so integer images hold it without clipping.
    inst->set_source(Frame::from_top_down(scene(w, h, 4), w, h, 4), kOfxImageUnPreMultiplied);
    RenderResult reference = inst->render(2, {0, 0, w, h});
    REQUIRE(reference.status == kOfxStatOK);
    auto [depth, tolerance] = GENERATE(table<std::string, float>({{kOfxBitDepthShort, 2e-3f}, {kOfxBitDepthByte, 0.1f}}));
    INFO(depth);
    inst->set_source_depth(depth);
    RenderResult r = inst->render(2, {0, 0, w, h});
    INFO(inst->effect().persistent_message);
    REQUIRE(r.status == kOfxStatOK);
    // The input is quantised too (scene values above 1 clip), so only pixels whose input
    // was inside 0-1 compare; their difference is bounded by the quantisation steps.
    const Frame input = Frame::from_top_down(scene(w, h, 4), w, h, 4);
    long compared = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float* in = input.at(x, y);
            if (std::max({in[0], in[1], in[2]}) > 1.0f) continue;
            ++compared;
            for (int c = 0; c < 4; ++c) REQUIRE(std::abs(r.output.at(x, y)[c] - reference.output.at(x, y)[c]) <= tolerance);
        }
    CHECK(compared > w * h / 2);
}

TEST_CASE("grain depends on the frame and the seed, never on the order frames are rendered in", "[plugin][determinism]") {
    const int w = 48, h = 40;
    Frame source = Frame::from_top_down(scene(w, h, 4), w, h, 4);
    auto a = make_instance(), b = make_instance();
    for (auto* inst : {a.get(), b.get()}) {
        set_common_look(*inst);
        inst->set_source(source);
    }
    RenderResult a3 = a->render(3, {0, 0, w, h}), a4 = a->render(4, {0, 0, w, h});
    RenderResult b4 = b->render(4, {0, 0, w, h}), b3 = b->render(3, {0, 0, w, h});
    CHECK(same_bits(a3.output, b3.output));
    CHECK(same_bits(a4.output, b4.output));
    CHECK_FALSE(same_bits(a3.output, a4.output));

    a->set_int("seed", 6);
    CHECK_FALSE(same_bits(a->render(3, {0, 0, w, h}).output, a3.output));
    a->set_int("staticGrain", 1);
    CHECK(same_bits(a->render(3, {0, 0, w, h}).output, a->render(4, {0, 0, w, h}).output));
}

TEST_CASE("changing Quality on an instance renders that tier, as a new instance does", "[plugin]") {
    const int w = 48, h = 40;
    Frame source = Frame::from_top_down(scene(w, h, 4), w, h, 4);
    auto switched = make_instance(), fresh = make_instance();
    for (auto* inst : {switched.get(), fresh.get()}) {
        set_common_look(*inst);
        inst->set_source(source);
    }
    switched->set_int("quality", switched->choice_index("quality", "fast"));
    RenderResult fast = switched->render(3, {0, 0, w, h});
    switched->set_int("quality", switched->choice_index("quality", "high"));
    fresh->set_int("quality", fresh->choice_index("quality", "high"));
    RenderResult high = switched->render(3, {0, 0, w, h});
    CHECK(same_bits(high.output, fresh->render(3, {0, 0, w, h}).output));
    CHECK_FALSE(same_bits(high.output, fast.output));  // the plan of the other tier is not reused
}

TEST_CASE("a saved node keeps its stocks when the plugin's list of stocks changes", "[plugin]") {
    const int w = 32, h = 24;
    Frame source = Frame::from_top_down(scene(w, h, 4), w, h, 4);
    auto chosen = make_instance();
    const int portra = chosen->choice_index("film", "Portra 400"), trix = chosen->choice_index("film", "Tri-X");
    REQUIRE(portra >= 0);
    REQUIRE(trix >= 0);
    REQUIRE(portra != trix);
    // A new node records the id of its default stock; a user's choice moves the id with it.
    CHECK(chosen->get_string("filmStock") == "kodak-vision3-250d");
    CHECK(chosen->get_string("paperStock") == "kodak-2383");
    chosen->set_int("film", portra);
    REQUIRE(chosen->user_edited("film") == kOfxStatOK);
    CHECK(chosen->get_string("filmStock") == "kodak-portra-400");
    chosen->set_source(source);
    RenderResult expected = chosen->render(2, {0, 0, w, h});
    REQUIRE(expected.status == kOfxStatOK);

    SECTION("a node saved when Portra was at another index develops through Portra") {
        // As if the list had changed: the saved index now shows Tri-X, the saved id says Portra.
        auto loaded = Plugin::get().create_instance([&](Instance& i) {
            i.set_int("film", trix);
            i.set_string("filmStock", "kodak-portra-400");
        });
        REQUIRE(loaded->create_status() == kOfxStatOK);
        CHECK(loaded->get_int("film") == portra);
        loaded->set_source(source);
        CHECK(same_bits(loaded->render(2, {0, 0, w, h}).output, expected.output));
    }
    SECTION("a node saved before the ids keeps its choice and records its id") {
        auto loaded = Plugin::get().create_instance([&](Instance& i) { i.set_int("film", portra); });
        CHECK(loaded->get_int("film") == portra);
        CHECK(loaded->get_string("filmStock") == "kodak-portra-400");
    }
    SECTION("a host that sets the saved id after creating the node") {
        auto loaded = make_instance();
        loaded->set_string("filmStock", "kodak-portra-400");
        REQUIRE(loaded->user_edited("filmStock") == kOfxStatOK);
        CHECK(loaded->get_int("film") == portra);
    }
    SECTION("a node saved with a stock this version does not have fails to render, naming it") {
        auto loaded = Plugin::get().create_instance([&](Instance& i) { i.set_string("filmStock", "kodak-ektachrome-e100"); });
        REQUIRE(loaded->create_status() == kOfxStatOK);
        loaded->set_source(source);
        CHECK(loaded->render(2, {0, 0, w, h}).status == kOfxStatFailed);
        CHECK(loaded->effect().persistent_message.find("kodak-ektachrome-e100") != std::string::npos);
        // Choosing a stock clears it.
        loaded->set_int("film", portra);
        REQUIRE(loaded->user_edited("film") == kOfxStatOK);
        CHECK(same_bits(loaded->render(2, {0, 0, w, h}).output, expected.output));
    }
    SECTION("a missing paper matters only to the Print output, the one that uses a paper") {
        auto loaded = Plugin::get().create_instance([&](Instance& i) { i.set_string("paperStock", "agfa-discontinued"); });
        loaded->set_source(source);
        CHECK(loaded->render(2, {0, 0, w, h}).status == kOfxStatFailed);
        CHECK(loaded->effect().persistent_message.find("agfa-discontinued") != std::string::npos);
        loaded->set_int("output", loaded->choice_index("output", "Negative"));
        CHECK(loaded->render(2, {0, 0, w, h}).status == kOfxStatOK);
    }
}

TEST_CASE("settings that change nothing are reported as identity", "[plugin]") {
    auto inst = make_instance();
    inst->set_source(Frame::from_top_down(scene(16, 16, 4), 16, 16, 4));
    CHECK(inst->is_identity(1) == kOfxStatReplyDefault);  // the default print

    inst->set_int("output", inst->choice_index("output", "Texture"));
    inst->set_int("grain", 0);
    inst->set_int("mtf", 0);
    inst->set_double("halation", 0);
    std::string clip;
    CHECK(inst->is_identity(1, &clip) == kOfxStatOK);
    CHECK(clip == "Source");

    SECTION("any one film effect makes it a render") {
        SECTION("grain") { inst->set_int("grain", 1); }
        SECTION("MTF") { inst->set_int("mtf", 1); }
        SECTION("halation") { inst->set_double("halation", 0.5); }
        SECTION("a colour conversion") { inst->set_string("outputColorspace", "ACEScg"); }
        CHECK(inst->is_identity(1) == kOfxStatReplyDefault);
    }
    SECTION("grain switched on at zero amount changes nothing") {
        inst->set_int("grain", 1);
        inst->set_double3("grainAmount", 0, 0, 0);
        CHECK(inst->is_identity(1) == kOfxStatOK);
    }
}

TEST_CASE("OCIO=ocio://default, as hosts set it for OCIO 2.2, renders with the embedded config", "[plugin]") {
    const int w = 32, h = 24;
    std::string message;
    auto render = [&](const std::string& config_parameter) {
        auto inst = make_instance();
        set_common_look(*inst);
        inst->set_string("inputColorspace", "sRGB - Texture");
        inst->set_string("outputColorspace", "ACEScg");
        inst->set_string("ocioConfig", config_parameter);
        inst->set_source(Frame::from_top_down(scene(w, h, 3), w, h, 3), kOfxImageOpaque);
        RenderResult r = inst->render(1, {0, 0, w, h});
        message = inst->effect().persistent_message;
        INFO(message);
        REQUIRE(r.status == kOfxStatOK);
        return r.output;
    };
    const Frame embedded = render("");
    CHECK(message.empty());
    {
        ScopedOcioVariable set(std::string("ocio://default"));
        CHECK(same_bits(render(""), embedded));
        // The node says which config it renders with, in the host's terms: no program flags.
        CHECK_THAT(message, Catch::Contains("ocio://default") && Catch::Contains("embedded"));
        CHECK(message.find("--") == std::string::npos);
    }
    CHECK(same_bits(render("ocio://default"), embedded));
    CHECK_THAT(message, Catch::Contains("OCIO config") && Catch::Contains("embedded"));
}

TEST_CASE("a reference render that will take hours says so on the node before it starts", "[plugin]") {
    const int w = 32, h = 24;
    auto inst = make_instance();
    set_common_look(*inst);  // a 4 mm frame: 125 um of film a pixel, ~10^7 silver grains each
    inst->set_int("quality", inst->choice_index("quality", "reference"));
    inst->set_source(Frame::from_top_down(scene(w, h, 4), w, h, 4));
    inst->effect().abort_after = 0;  // the user stops it as soon as it starts
    CHECK(inst->render(1, {0, 0, w, h}).status == kOfxStatFailed);
    INFO(inst->effect().persistent_message);
    CHECK(inst->effect().persistent_message_type == kOfxMessageWarning);
    CHECK(inst->effect().persistent_message.find("Quality reference draws every silver grain") != std::string::npos);
    CHECK(inst->effect().persistent_message.find("CPU hours") != std::string::npos);

    // At a 4K frame's pitch (6 um of film a pixel) it is a quick render, and nothing is said.
    inst->set_double("frameWidthMm", 0.195);
    inst->set_double("printWidthMm", 0.175);
    CHECK(inst->user_edited("printWidthMm") == kOfxStatOK);  // the host clears the node's message
    CHECK(inst->render(1, {0, 0, w, h}).status == kOfxStatFailed);
    CHECK(inst->effect().persistent_message.empty());

    // Across a 150 mm frame it would take days: refused before it starts, an error on the node.
    inst->set_double("frameWidthMm", 150);
    inst->set_double("printWidthMm", 150);
    CHECK(inst->render(1, {0, 0, w, h}).status == kOfxStatFailed);
    INFO(inst->effect().persistent_message);
    CHECK(inst->effect().persistent_message_type == kOfxMessageError);
    CHECK(inst->effect().persistent_message.find("Quality reference") != std::string::npos);
    CHECK(inst->effect().persistent_message.find("budget of 24 CPU hours") != std::string::npos);
}

TEST_CASE("abort stops a render", "[plugin]") {
    const int w = 32, h = 256;  // several row bands
    auto inst = make_instance();
    set_common_look(*inst);
    inst->set_source(Frame::from_top_down(scene(w, h, 4), w, h, 4));
    set_cpu_count(1);

    inst->effect().abort_after = 0;
    RenderResult none = inst->render(1, {0, 0, w, h});
    CHECK(none.status == kOfxStatFailed);
    CHECK(count_value(none.output, -7.0f) == (long)none.output.pixels.size());

    inst->effect().abort_calls = 0;
    inst->effect().abort_after = 1;
    RenderResult part = inst->render(1, {0, 0, w, h});
    CHECK(part.status == kOfxStatFailed);
    long untouched = count_value(part.output, -7.0f);
    CHECK(untouched > 0);
    CHECK(untouched < (long)part.output.pixels.size());
    CHECK(inst->effect().persistent_message.empty());

    inst->effect().abort_after = -1;
    CHECK(inst->render(1, {0, 0, w, h}).status == kOfxStatOK);
    set_cpu_count(4);
    CHECK(outstanding_allocations() == 0);
    CHECK(outstanding_images() == 0);
}

TEST_CASE("bad parameter values are rejected with a message naming them", "[plugin][bad-input]") {
    const int w = 24, h = 16;
    auto inst = make_instance();
    inst->set_source(Frame::from_top_down(scene(w, h, 4), w, h, 4));
    fs::create_directories(kTmp);
    const std::string bad_json = (kTmp / "bad-stock.json").string();
    std::ofstream(bad_json) << "{ \"format\": \"darkroom-stock\", ";
    std::string expected;

    SECTION("exposure not a number") {
        inst->set_double("exposure", NAN);
        expected = "Exposure (EV)";
    }
    SECTION("exposure out of range") {
        inst->set_double("exposure", 1e6);
        expected = "Exposure (EV)";
    }
    SECTION("negative grain amount") {
        inst->set_double3("grainAmount", 1, -1, 1);
        expected = "Amount";
    }
    SECTION("a film option that does not exist") {
        inst->set_int("film", 99);
        expected = "Film";
    }
    SECTION("a stock file option with no file") {
        inst->set_int("film", inst->choice_index("film", "Stock file"));
        expected = "Film stock file";
    }
    SECTION("a stock file that does not exist") {
        inst->set_int("film", inst->choice_index("film", "Stock file"));
        inst->set_string("filmFile", "/nonexistent/film.json");
        expected = "/nonexistent/film.json";
    }
    SECTION("a stock file that is not a stock") {
        inst->set_int("paper", inst->choice_index("paper", "Stock file"));
        inst->set_string("paperFile", bad_json);
        expected = bad_json;
    }
    SECTION("a print with no paper") {
        inst->set_int("paper", inst->choice_index("paper", "None"));
        expected = "needs a paper";
    }
    SECTION("an unknown colour space") {
        inst->set_string("inputColorspace", "no-such-space");
        expected = "no-such-space";
    }
    SECTION("an OCIO config that does not exist") {
        inst->set_string("ocioConfig", "/nonexistent/config.ocio");
        expected = "/nonexistent/config.ocio";
    }
    RenderResult r = inst->render(1, {0, 0, w, h});
    CHECK(r.status == kOfxStatFailed);
    CHECK_THAT(inst->effect().persistent_message, Catch::Contains(expected));
    CHECK(count_value(r.output, -7.0f) == (long)r.output.pixels.size());
    CHECK(outstanding_allocations() == 0);
    CHECK(outstanding_images() == 0);

    // Corrected, it renders and the message goes.
    inst->set_double("exposure", 0);
    inst->set_double3("grainAmount", 1, 1, 1);
    inst->set_int("film", inst->choice_index("film", "Tri-X"));
    inst->set_int("paper", inst->choice_index("paper", "grade 2"));
    inst->set_string("inputColorspace", "scene_linear");
    inst->set_string("ocioConfig", "");
    CHECK(inst->render(1, {0, 0, w, h}).status == kOfxStatOK);
    CHECK(inst->effect().persistent_message.empty());
}

TEST_CASE("bad input fails with a message, never a crash", "[plugin][bad-input]") {
    const int w = 24, h = 16;
    auto inst = make_instance();
    inst->set_source(Frame::from_top_down(scene(w, h, 4), w, h, 4));
    RenderResult r;
    std::string expected;

    SECTION("no input") {
        inst->disconnect_source();
        r = inst->render(1, {0, 0, w, h});
        expected = "Source";
    }
    SECTION("a zero-size render window") {
        r = inst->render(1, {5, 5, 5, 9});
        expected = "empty window";
    }
    SECTION("a render window far outside the output image") {
        OfxRectI output{0, 0, w, h};
        r = inst->render(1, {-1000000000, -1000000000, 1000000000, 1000000000}, 1.0, &output);
        expected = "not inside the output image";
    }
    SECTION("a huge frame") {
        inst->set_source_rod({0, 0, 1e7, 1e7});
        r = inst->render(1, {0, 0, w, h});
        expected = "pixels a side";
    }
    SECTION("an unsupported pixel depth") {
        inst->set_source_depth(kOfxBitDepthHalf);
        r = inst->render(1, {0, 0, w, h});
        expected = "pixel depth";
    }
    CHECK(r.status == kOfxStatFailed);
    CHECK_THAT(inst->effect().persistent_message, Catch::Contains(expected));
    CHECK(outstanding_allocations() == 0);
    CHECK(outstanding_images() == 0);
}

// A predicted (Cineon log) profile as if measured on linear plates, as the effect's output is.
void as_linear_profile(const std::string& path) {
    nlohmann::json profile;
    std::ifstream(path) >> profile;
    profile["encoding"] = "linear";
    std::ofstream(path) << profile.dump();
}

TEST_CASE("a grain profile replaces the stock's grain as darkroom develop --grain-profile does, in any tiles",
          "[plugin][cli][grain]") {
    const int w = 64, h = 48;
    std::vector<float> px = scene(w, h, 3);
    std::string input = write_exr("plugin-profile-scene.exr", px, w, h, 3);
    std::string profile = (fs::path(DARKROOM_TEST_TMP) / "plugin-profile.json").string();
    REQUIRE(std::system((std::string(DARKROOM_EXE) + " grain predict --stock kodak-tri-x-400 --width 512 -o " + profile +
                         " > /dev/null")
                            .c_str()) == 0);
    as_linear_profile(profile);
    auto inst = make_instance();
    set_common_look(*inst);
    inst->set_string("grainProfile", profile);
    inst->set_source(Frame::from_top_down(px, w, h, 3), kOfxImageOpaque);
    set_cpu_count(1);
    RenderResult full = inst->render(9, {0, 0, w, h});
    INFO(inst->effect().persistent_message);
    REQUIRE(full.status == kOfxStatOK);
    std::vector<float> cli = develop(input, kCommonFlags + " --frame 9 --grain-profile " + profile);
    std::vector<float> ofx = full.output.to_top_down();
    REQUIRE(ofx.size() == cli.size());
    long differing = 0;
    for (size_t i = 0; i < cli.size(); ++i) differing += ofx[i] != cli[i];
    CHECK(differing == 0);
    set_cpu_count(3);
    RenderResult tiles = inst->render_tiles(9, {0, 0, w, h}, 23, 17);
    REQUIRE(tiles.status == kOfxStatOK);
    CHECK(same_bits(full.output, tiles.output));
    // The planned profile is kept between renders, by the file's version: one edited (another
    // stock's grain, a later modification time) is read again.
    const auto written = fs::last_write_time(profile);
    REQUIRE(std::system((std::string(DARKROOM_EXE) + " grain predict --stock kodak-vision3-500t --width 512 -o " +
                         profile + " > /dev/null")
                            .c_str()) == 0);
    as_linear_profile(profile);
    fs::last_write_time(profile, written + std::chrono::seconds(2));
    RenderResult edited = inst->render(9, {0, 0, w, h});
    REQUIRE(edited.status == kOfxStatOK);
    CHECK_FALSE(same_bits(full.output, edited.output));
    CHECK(edited.output.to_top_down() == develop(input, kCommonFlags + " --frame 9 --grain-profile " + profile));
    set_cpu_count(4);
    inst->set_string("grainProfile", "/nonexistent-profile.json");
    RenderResult bad = inst->render(9, {0, 0, w, h});
    CHECK(bad.status == kOfxStatFailed);
    CHECK_THAT(inst->effect().persistent_message, Catch::Contains("nonexistent-profile.json"));
    // A profile of two channels fits neither the output's RGB nor a grey image: refused at
    // once, naming it (not applied to red and green).
    nlohmann::json two;
    {
        std::ifstream f(profile);
        two = nlohmann::json::parse(f);
    }
    two["channels"].erase(2);
    two["channel_correlation"] = {{1.0, 1.0}, {1.0, 1.0}};
    const std::string two_path = (fs::path(DARKROOM_TEST_TMP) / "plugin-profile-two.json").string();
    std::ofstream(two_path) << two.dump();
    inst->set_string("grainProfile", two_path);
    bad = inst->render(9, {0, 0, w, h});
    CHECK(bad.status == kOfxStatFailed);
    CHECK_THAT(inst->effect().persistent_message, Catch::Contains(two_path) && Catch::Contains("2 channels"));
}

// --- The look layer: the node's parameters are the table's, and look files travel -------

TEST_CASE("every setting of the look's table is a node parameter with its default, range and help", "[plugin][look]") {
    Effect& ctx = Plugin::get().context_descriptor();
    using darkroom::ParameterType;
    for (const darkroom::Parameter& row : darkroom::parameters()) {
        if (row.ofx_name.empty()) continue;
        INFO(row.key);
        const Param* param = ctx.params.find(row.ofx_name);
        REQUIRE(param);
        const PropertySet& props = param->props;
        CHECK(props.get_string(kOfxParamPropHint) == row.help);
        CHECK(props.get_string(kOfxPropLabel) == row.label);
        const nlohmann::json def = row.default_value();
        switch (row.type) {
            case ParameterType::number:
            case ParameterType::per_channel: {
                const int dims = row.type == ParameterType::per_channel ? 3 : 1;
                for (int i = 0; i < dims; ++i) {
                    CHECK(props.get_double(kOfxParamPropMin, i) == row.min);
                    CHECK(props.get_double(kOfxParamPropMax, i) == row.max);
                    if (!def.is_null())
                        CHECK(props.get_double(kOfxParamPropDefault, i) == (dims == 3 ? def[size_t(i)] : def).get<double>());
                }
                CHECK(props.get_int(kOfxParamPropAnimates) == int(row.animatable));
                break;
            }
            case ParameterType::on_off: CHECK(props.get_int(kOfxParamPropDefault) == int(def.get<bool>())); break;
            case ParameterType::choice:
                CHECK(row.choices.at(size_t(props.get_int(kOfxParamPropDefault))).name == def);
                break;
            case ParameterType::stock: {
                // The default option is the default stock, labelled with its role.
                const auto& options = props.props.at(kOfxParamPropChoiceOption).s;
                const std::string label = options.at(size_t(props.get_int(kOfxParamPropDefault)));
                CHECK(darkroom::find_stock(def.get<std::string>()).name == label.substr(label.find(": ") + 2));
                break;
            }
            case ParameterType::seed: CHECK(uint64_t(props.get_int(kOfxParamPropDefault)) == def.get<uint64_t>()); break;
            default: CHECK(props.get_string(kOfxParamPropDefault) == def.get<std::string>()); break;
        }
    }
    // The print stage lists print films and papers by role: the program's default print is there.
    const auto& papers = ctx.params.find("paper")->props.props.at(kOfxParamPropChoiceOption).s;
    CHECK(std::count_if(papers.begin(), papers.end(), [](const std::string& o) { return o.rfind("Print film: ", 0) == 0; }) >= 1);
    CHECK(std::count_if(papers.begin(), papers.end(), [](const std::string& o) { return o.rfind("Paper: ", 0) == 0; }) >= 1);
    // The film lists negatives, then reversal (slide) films, by role.
    const auto& films = ctx.params.find("film")->props.props.at(kOfxParamPropChoiceOption).s;
    const auto role_of = [&](const char* role) {
        return std::find_if(films.begin(), films.end(), [&](const std::string& o) { return o.rfind(role, 0) == 0; });
    };
    CHECK(role_of("Negative: ") < role_of("Reversal: "));
    CHECK(role_of("Reversal: ") != films.end());
}

TEST_CASE("a look file renders the program's pixels in the node, every output mode", "[plugin][look][cli]") {
    const int w = 48, h = 32;
    std::vector<float> px = scene(w, h, 3);
    const std::string input = write_exr("plugin-look-scene.exr", px, w, h, 3);
    const std::string output = GENERATE(as<std::string>{}, "print", "negative", "density", "scan", "texture");
    INFO("output " << output);
    const std::string look = (kTmp / ("look-" + output + ".json")).string();
    run(std::string(DARKROOM_EXE) + " develop --output " + output +
        " --film kodak-portra-400 --paper kodak-portra-endura --grain-amount 1.5 --seed 5 --frame-width-mm 4 "
        "--print-width-mm 30 --exposure 0.5 --print-exposure -0.3 --save-look " + look);
    auto inst = make_instance();
    inst->set_string("lookFile", look);
    REQUIRE(inst->user_edited("loadLook") == kOfxStatOK);
    CHECK(inst->get_string("filmStock") == "kodak-portra-400");
    inst->set_source(Frame::from_top_down(px, w, h, 3), kOfxImageOpaque);
    RenderResult r = inst->render(7, {0, 0, w, h});
    INFO(inst->effect().persistent_message);
    REQUIRE(r.status == kOfxStatOK);
    const std::vector<float> cli = develop(input, "--look " + look + " --frame 7");
    CHECK(r.output.to_top_down() == cli);
}

TEST_CASE("a look the node saves is read by the program, and the node reads the program's", "[plugin][look][cli]") {
    const int w = 40, h = 30;
    std::vector<float> px = scene(w, h, 3);
    const std::string input = write_exr("plugin-save-scene.exr", px, w, h, 3);
    auto inst = make_instance();
    set_common_look(*inst);
    inst->set_double3("printerLights", 24, 26, 25);
    inst->set_int("grainResponseOverride", 1);
    inst->set_double3("grainResponse", 0.4, 0.5, 0.6);
    inst->set_int("output", inst->choice_index("output", "Scan"));
    const std::string look = (kTmp / "node-look.json").string();
    fs::remove(look);
    inst->set_string("lookFile", look);
    REQUIRE(inst->user_edited("saveLook") == kOfxStatOK);
    REQUIRE(fs::exists(look));
    inst->set_source(Frame::from_top_down(px, w, h, 3), kOfxImageOpaque);
    RenderResult r = inst->render(3, {0, 0, w, h});
    REQUIRE(r.status == kOfxStatOK);
    CHECK(r.output.to_top_down() == develop(input, "--look " + look + " --frame 3"));

    // Read back into a fresh node: the same parameters, so the same pixels.
    auto reloaded = make_instance();
    reloaded->set_string("lookFile", look);
    REQUIRE(reloaded->user_edited("loadLook") == kOfxStatOK);
    CHECK(reloaded->get_int("output") == inst->get_int("output"));
    CHECK(reloaded->get_int("grainResponseOverride") == 1);
    reloaded->set_source(Frame::from_top_down(px, w, h, 3), kOfxImageOpaque);
    CHECK(same_bits(reloaded->render(3, {0, 0, w, h}).output, r.output));

    SECTION("a look file that cannot be read is named on the node") {
        reloaded->set_string("lookFile", (kTmp / "no-such-look.json").string());
        CHECK(reloaded->user_edited("loadLook") == kOfxStatFailed);
        CHECK_THAT(reloaded->effect().persistent_message, Catch::Contains("no-such-look.json"));
    }
}
