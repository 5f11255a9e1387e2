// Colour management in the darkroom program: the OCIO flags of develop, the config
// precedence, and bake-lut's LUT applied by the real oiiotool against develop itself.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iterator>
#include <optional>
#include <utility>

#include "cli_support.h"
#include "../ocio/ocio_variable.h"

using namespace darkroom_test;

namespace {

bool oiiotool_available() { return std::system("oiiotool --help > /dev/null 2>&1") == 0; }

std::string tmp(const std::string& name) { return (kTmp / name).string(); }

// The embedded config as a file, written by darkroom itself, for oiiotool.
std::string written_config(const std::string& name) {
    const std::string path = tmp(name);
    Result r = darkroom("colorconfig -o " + path);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    return path;
}

// Runs oiiotool with `config` active ($OCIO unset); REQUIREs success.
void oiiotool(const std::string& config, const std::string& args) {
    ScopedOcioVariable unset(std::nullopt);
    const std::string command = "oiiotool --colorconfig " + config + " " + args;
    INFO(command);
    REQUIRE(std::system(command.c_str()) == 0);
}

double max_difference(const std::vector<float>& a, const std::vector<float>& b) {
    REQUIRE(a.size() == b.size());
    double m = 0;
    for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(double(a[i]) - double(b[i])));
    return m;
}

// sRGB encoding (IEC 61966-2-1), the closed form.
double srgb_encode(double linear) {
    return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

// A scene for the LUT test: greys every quarter stop from -8 to +8 stops around 0.18,
// then every combination of R, G and B at -8, -6, ..., +8 stops (729 colours, from
// neutral to strongly saturated), then channels at exactly 0.
std::string make_lut_scene(const std::string& name) {
    std::vector<float> rgb;
    for (int q = -32; q <= 32; ++q) rgb.insert(rgb.end(), 3, float(0.18 * std::exp2(q / 4.0)));
    for (int b = -8; b <= 8; b += 2)
        for (int g = -8; g <= 8; g += 2)
            for (int r = -8; r <= 8; r += 2)
                for (int stops : {r, g, b}) rgb.push_back(float(0.18 * std::exp2(stops)));
    for (float v : {0.0f, 0.18f, 2.0f})
        for (int zero = 0; zero < 3; ++zero)
            for (int c = 0; c < 3; ++c) rgb.push_back(c == zero ? 0.0f : v);
    const int width = 32, height = int((rgb.size() / 3 + width - 1) / width);
    rgb.resize(size_t(width) * height * 3, 0.18f);
    const std::string path = tmp(name);
    OIIO::ImageBuf buf(OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::FLOAT));
    buf.set_pixels(buf.roi(), OIIO::TypeDesc::FLOAT, rgb.data());
    REQUIRE(buf.write(path));
    return path;
}

}  // namespace

TEST_CASE("develop converts the input to the working space and the result to the output", "[cli][colour]") {
    if (!oiiotool_available()) {
        WARN("oiiotool is not installed: skipped");
        return;
    }
    ScopedOcioVariable unset(std::nullopt);
    const std::string config = written_config("colour-convert.ocio");
    const std::string in = make_input("colour-convert-in.exr"), base = tmp("colour-convert-base.exr");
    const std::string look = " --no-grain --frame-width-mm 4 --print-width-mm 30";
    REQUIRE(darkroom("develop " + in + " -o " + base + look).exit_code == 0);
    const std::vector<float> base_pixels = pixels(base);

    SECTION("--iscolorspace: the same picture in ACEScg develops the same") {
        const std::string acescg = tmp("colour-convert-acescg.exr"), out = tmp("colour-convert-from-acescg.exr");
        oiiotool(config, in + " --colorconvert lin_rec709 ACEScg -o " + acescg);
        Result r = darkroom("develop " + acescg + " -o " + out + look + " --iscolorspace ACEScg");
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        CHECK(max_difference(pixels(out), base_pixels) < 1e-4);
    }
    SECTION("--ociodisplay sRGB Standard is the sRGB encoding of the print") {
        const std::string out = tmp("colour-convert-display.exr");
        REQUIRE(darkroom("develop " + in + " -o " + out + look + " --ociodisplay sRGB Standard").exit_code == 0);
        std::vector<float> expected = base_pixels;
        for (float& v : expected) v = float(srgb_encode(v));
        CHECK(max_difference(pixels(out), expected) < 1e-4);
    }
    SECTION("--tocolorspace ACEScg is oiiotool's conversion of the print") {
        const std::string out = tmp("colour-convert-to-acescg.exr"), expected = tmp("colour-convert-expected.exr");
        REQUIRE(darkroom("develop " + in + " -o " + out + look + " --tocolorspace ACEScg").exit_code == 0);
        oiiotool(config, base + " --colorconvert lin_rec709 ACEScg -o " + expected);
        CHECK(max_difference(pixels(out), pixels(expected)) < 1e-5);
    }
}

// The embedded config written out, with the alias "srgb" moved from 'sRGB - Texture' to
// 'Rec.709 - Camera': a picture read as "srgb" shows which config was used.
std::string show_config(const std::string& name) {
    const std::string path = written_config(name);
    std::ifstream in(path);
    std::string yaml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"aliases: [sRGB, srgb_tx", "aliases: [srgb_tx"},
                                   {"aliases: [rec709, ", "aliases: [srgb, rec709, "}}) {
        REQUIRE(yaml.find(from) != std::string::npos);
        yaml.replace(yaml.find(from), from.size(), to);
    }
    std::ofstream(path) << yaml;
    return path;
}

// The output's "oiio:ColorSpace" names the space its pixels are in. The input's tag ("sRGB",
// as an 8-bit picture carries) is never passed on. (PNG stores any name; EXR stores none.)
TEST_CASE("the output is tagged with the colour space its pixels are in", "[cli][colour][metadata]") {
    ScopedOcioVariable unset(std::nullopt);
    const std::string in = tmp("colour-tag-in.png");
    OIIO::ImageSpec spec(16, 12, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    OIIO::ImageBuf buf(spec);
    OIIO::ImageBufAlgo::fill(buf, {0.4f, 0.4f, 0.4f});
    REQUIRE(buf.write(in));
    auto tag_of = [&](const std::string& name, const std::string& flags) {
        const std::string out = tmp(name);
        Result r = darkroom("develop " + in + " -o " + out + " --no-grain" + flags);
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        auto file = OIIO::ImageInput::open(out);
        REQUIRE(file);
        const OIIO::ParamValue* tag = file->spec().find_attribute("oiio:ColorSpace");
        return tag ? std::string(tag->get_string()) : std::string("(none)");
    };
    CHECK(tag_of("colour-tag-print.png", "") == "lin_rec709");
    CHECK(tag_of("colour-tag-acescg.png", " --tocolorspace lin_ap1") == "ACEScg");  // the config's name, not the alias
    CHECK(tag_of("colour-tag-display.png", " --ociodisplay sRGB Standard") == "sRGB - Display");
    CHECK(tag_of("colour-tag-scan.png", " --output scan") == "Cineon Log");
    CHECK(tag_of("colour-tag-density.tif", " --output density -d float") == "(none)");
}

TEST_CASE("verbose output names the active config and why, and the config used is the one named", "[cli][colour]") {
    const std::string in = make_input("colour-config-in.exr", 16, 12), config = show_config("colour-config.ocio");
    const std::string develop = "develop " + in + " --no-grain -v --iscolorspace srgb -o ";
    auto run = [&](const std::string& out, const std::string& flags, const std::string& active,
                   const std::string& input) {
        Result r = darkroom(develop + tmp(out) + flags);
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        CHECK_THAT(r.output, Catch::Contains(active));
        CHECK_THAT(r.output, Catch::Contains("input: '" + input + "' -> 'lin_rec709'"));
        return pixels(tmp(out));
    };
    std::vector<float> embedded, by_flag, by_variable;
    {
        ScopedOcioVariable unset(std::nullopt);
        embedded = run("colour-config-embedded.exr", "",
                       "the embedded Darkroom config (no --colorconfig was given and $OCIO is not set)",
                       "sRGB - Texture");
        by_flag = run("colour-config-flag.exr", " --colorconfig " + config,
                      "OCIO config '" + config + "' (given by --colorconfig)", "Rec.709 - Camera");
    }
    {
        ScopedOcioVariable set(config);
        by_variable = run("colour-config-variable.exr", "", "OCIO config '" + config + "' ($OCIO names it",
                          "Rec.709 - Camera");
        // The flag wins over $OCIO, and a bad one is an error, not the embedded config.
        Result r = darkroom(develop + tmp("colour-config-never.exr") + " --colorconfig " + tmp("no-such.ocio"));
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.output, Catch::Contains("no-such.ocio") && Catch::Contains("does not exist"));
        CHECK_FALSE(fs::exists(tmp("colour-config-never.exr")));
    }
    CHECK(by_flag == by_variable);
    CHECK(max_difference(by_flag, embedded) > 0.01);  // the BT.709 and sRGB curves differ
}

TEST_CASE("a built-in config name OCIO 2.1 cannot load (OCIO=ocio://default) gives the embedded config, with a warning",
          "[cli][colour]") {
    const std::string in = make_input("colour-builtin-in.exr", 16, 12);
    const std::string develop = "develop " + in + " --iscolorspace srgb --ociodisplay sRGB Standard -o ";
    std::vector<float> embedded;
    {
        ScopedOcioVariable unset(std::nullopt);
        Result r = darkroom(develop + tmp("colour-builtin-unset.exr"));
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        CHECK_THAT(r.output, !Catch::Contains("warning"));
        embedded = pixels(tmp("colour-builtin-unset.exr"));
    }
    auto check_falls_back = [&](const std::string& out, const std::string& flags, const std::string& origin) {
        Result r = darkroom(develop + tmp(out) + flags);
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        CHECK_THAT(r.output, Catch::Contains("darkroom: warning: " + origin + " names 'ocio://default'") &&
                                 Catch::Contains("using the embedded Darkroom config"));
        CHECK(std::count(r.output.begin(), r.output.end(), '\n') == 1);  // one line
        CHECK(pixels(tmp(out)) == embedded);
    };
    {
        ScopedOcioVariable set(std::string("ocio://default"));
        check_falls_back("colour-builtin-variable.exr", "", "$OCIO");
    }
    {
        ScopedOcioVariable unset(std::nullopt);
        check_falls_back("colour-builtin-flag.exr", " --colorconfig ocio://default", "--colorconfig");
    }
}

TEST_CASE("colour conversions keep a window equal to that window of the full render", "[cli][colour][determinism]") {
    const std::string in = make_input("colour-window-in.exr", 80, 60), full = tmp("colour-window-full.exr"),
                      part = tmp("colour-window-part.exr");
    const std::string look = " --seed 5 --frame 12 --frame-width-mm 4 --print-width-mm 30 --iscolorspace ACEScct"
                             " --ociodisplay sRGB 'ACES 1.0 - SDR Video'";
    REQUIRE(darkroom("develop " + in + " -o " + full + look + " --threads 1").exit_code == 0);
    REQUIRE(darkroom("develop " + in + " -o " + part + look + " --threads 2 --window 17,9,40,30").exit_code == 0);
    std::vector<float> f = pixels(full), p = pixels(part);
    for (int y = 0; y < 30; ++y)
        for (int x = 0; x < 40; ++x)
            for (int c = 0; c < 3; ++c) REQUIRE(p[(y * 40 + x) * 3 + c] == f[((y + 9) * 80 + x + 17) * 3 + c]);
}

TEST_CASE("bad colour input: a message naming the config and the problem, and no output",
          "[cli][colour][bad-input]") {
    ScopedOcioVariable unset(std::nullopt);
    const std::string in = make_input("colour-bad-in.exr", 16, 12), out = tmp("colour-never.exr");
    const std::string garbage = tmp("colour-garbage.ocio"), no_displays = tmp("colour-no-displays.ocio");
    std::ofstream(garbage) << "this: [is not: an OCIO config\n";
    std::ofstream(no_displays) << "ocio_profile_version: 2.1\n"
                                  "roles:\n  default: lin_rec709\n  scene_linear: lin_rec709\n"
                                  "file_rules:\n  - !<Rule> {name: Default, colorspace: default}\n"
                                  "displays: {}\n"
                                  "colorspaces:\n  - !<ColorSpace>\n    name: lin_rec709\n";
    fs::remove(out);
    fs::remove(tmp("colour-never.cube"));
    struct Case {
        std::string args, message;
    };
    const std::string develop = "develop " + in + " -o " + out + " ";
    for (const Case& c : std::vector<Case>{
             {develop + "--iscolorspace NoSuchSpace", "unknown colour space 'NoSuchSpace'"},
             {develop + "--iscolorspace NoSuchSpace", "'ACEScg'"},  // lists the known names
             {develop + "--tocolorspace NoSuchSpace", "the embedded Darkroom config"},
             {develop + "--ociodisplay Cinema Standard", "unknown display 'Cinema'"},
             {develop + "--ociodisplay sRGB Filmic", "unknown view 'Filmic'"},
             {develop + "--colorconfig " + garbage, "colour-garbage.ocio' (from --colorconfig) cannot be read"},
             {develop + "--colorconfig " + no_displays, "colour-no-displays.ocio"},
             {develop + "--colorconfig " + no_displays, "no default display"},
             {develop + "--output density --tocolorspace ACEScg", "densities, which are data"},
             {develop + "--tocolorspace ACEScg --ociodisplay sRGB Standard", "both say where the result goes"},
             {"bake-lut -o " + tmp("colour-never.3dl"), ".cube or .clf"},
             {"bake-lut -o " + tmp("colour-never.cube") + " --input-units lux-seconds", "scene-linear"},
             {"bake-lut -o " + tmp("no-such-dir/look.cube"), "the folder '" + tmp("no-such-dir") + "' does not exist"},
             {"colorconfig -o " + tmp("no-such-dir/c.ocio"), "the folder '" + tmp("no-such-dir") + "' does not exist"},
         }) {
        Result r = darkroom(c.args);
        INFO(c.args << "\n" << r.output);
        CHECK(r.exit_code != 0);
        CHECK_THAT(r.output, Catch::Contains(c.message));
    }
    {
        ScopedOcioVariable set(tmp("colour-missing-env.ocio"));
        Result r = darkroom(develop);
        INFO(r.output);
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.output, Catch::Contains("colour-missing-env.ocio' (from $OCIO) does not exist"));
    }
    CHECK_FALSE(fs::exists(out));
    CHECK_FALSE(fs::exists(tmp("colour-never.cube")));
}

// A .clf holds the look's stages as the model composes them (exposure matrix, log, each
// layer's H&D curve, and for a colour print the print from the negative's densities as the
// one 3D LUT), so only the print is sampled, on the lattice the fast tier's own print table
// has: it matches develop within rounding. A .cube samples the whole look after a log2
// shaper: on the colour print's extreme colours (channels up to 16 stops apart) it misses
// by several per cent at the worst (docs/development/luts.md).
TEST_CASE("a LUT from bake-lut, applied by oiiotool, matches develop without grain, MTF and halation",
          "[cli][colour][lut]") {
    if (!oiiotool_available()) {
        WARN("oiiotool is not installed: skipped");
        return;
    }
    ScopedOcioVariable unset(std::nullopt);
    const std::string config = written_config("colour-lut.ocio");
    const std::string scene = make_lut_scene("colour-lut-scene.exr");
    const std::string bw_look = " --film kodak-tri-x-400 --paper vdr-paper-grade-2 --exposure 0.5 --print-exposure -0.3";
    const std::string colour_look = " --film kodak-vision3-250d --paper kodak-2383 --exposure 0.5";
    const std::string display = " --ociodisplay sRGB Standard";
    struct Case {
        const char* lut;
        const char* input_space;  // "" for the working space
        std::string look;         // with the output and its colour flags
        std::string bake_flags = "";
    };
    for (const Case& c : {Case{"colour-look.cube", "", bw_look + display}, Case{"colour-look.clf", "", bw_look + display},
                          Case{"colour-look-acescct.clf", "ACEScct", bw_look + display},
                          Case{"colour-look-acescct.cube", "ACEScct", bw_look + display},
                          Case{"colour-look-2383.clf", "", colour_look + display},
                          Case{"colour-look-2383.cube", "", colour_look + display},
                          Case{"colour-look-2383-acescct.clf", "ACEScct", colour_look + display},
                          // (The print's 3D LUT is the plan's table's lattice, whatever --size.)
                          // (Without DIR couplers: with them the look is sampled at --size.)
                          Case{"colour-look-2383-33.clf", "", colour_look + display + " --dir-couplers 0", " --size 33"},
                          Case{"colour-look-2383-high.clf", "", colour_look + display + " --quality high"},
                          Case{"colour-look-negative.clf", "", colour_look + " --output negative"},
                          Case{"colour-look-scan.clf", "", colour_look + " --output scan"},
                          Case{"colour-look-density.clf", "", colour_look + " --output density"},
                          Case{"colour-look-bw-negative.clf", "", bw_look + " --output negative"}}) {
        std::string in = scene, look = c.look;
        if (*c.input_space) {
            in = tmp(std::string("colour-lut-scene-") + c.input_space + ".exr");
            oiiotool(config, scene + " --colorconvert lin_rec709 " + c.input_space + " -o " + in);
            look += std::string(" --iscolorspace ") + c.input_space;
        }
        const std::string lut = tmp(c.lut), developed = tmp(std::string(c.lut) + ".developed.exr"),
                          applied = tmp(std::string(c.lut) + ".applied.exr");
        Result r = darkroom("bake-lut -o " + lut + look + c.bake_flags);
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        const bool clf = lut.substr(lut.size() - 4) == ".clf";
        // A .clf holds the stages: the curves as a 1D LUT, and a 3D LUT for a colour print only.
        const bool colour_print =
            c.look.find("kodak-2383") != std::string::npos && c.look.find("--output") == std::string::npos;
        // (The high tier's print is per pixel: no table of the plan's to hold, so it is sampled.)
        const bool high = c.look.find("--quality high") != std::string::npos;
        // (A colour negative's DIR couplers develop each layer from all three exposures: sampled.)
        const bool couplers = c.look.find("kodak-vision3-250d") != std::string::npos &&
                              c.look.find("--dir-couplers 0") == std::string::npos;
        const bool layered = clf && !high && !couplers;
        CHECK((r.output.find("1D curves") != std::string::npos) == layered);
        if (layered) CHECK((r.output.find("3D LUT") != std::string::npos) == colour_print);
        r = darkroom("develop " + in + " -o " + developed + look +
                     " --no-grain --no-mtf --halation 0 --dir-coupler-spread 0");
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        oiiotool(config, in + " --ociofiletransform " + lut + " -d float -o " + applied);

        // Display code values (or the output's values), full scale 1.
        const std::vector<float> want = pixels(developed), got = pixels(applied);
        REQUIRE(want.size() == got.size());
        std::vector<double> errors;
        for (size_t i = 0; i < want.size(); ++i) errors.push_back(std::abs(double(got[i]) - double(want[i])));
        std::sort(errors.begin(), errors.end());
        double mean = std::accumulate(errors.begin(), errors.end(), 0.0) / double(errors.size());
        double p99 = errors[errors.size() * 99 / 100], max_error = errors.back();
        std::printf("[bake-lut] %-28s input %-10s oiiotool vs develop: max %.5f, 99th percentile %.5f, mean %.6f\n",
                    c.lut, *c.input_space ? c.input_space : "lin_rec709", max_error, p99, mean);
        if (layered || (!colour_print && !couplers))
            CHECK(max_error < 0.005);
        else
            CHECK(p99 < 0.01);
        CHECK(mean < 0.001);
    }
}

// An input whose own tag names another colour space than the one its pixels are read as (an
// sRGB PNG without --iscolorspace), and linear values written to an integer file, are warned
// of, naming the flag that fixes them; where nothing is wrong, nothing is said.
TEST_CASE("develop warns of an input read in another space than its tag and of linear values in integers",
          "[cli][colour]") {
    ScopedOcioVariable unset(std::nullopt);
    const std::string png = tmp("colour-warn-in.png"), exr = make_input("colour-warn-in.exr");
    OIIO::ImageSpec spec(16, 12, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    OIIO::ImageBuf buf(spec);
    OIIO::ImageBufAlgo::fill(buf, {0.4f, 0.4f, 0.4f});
    REQUIRE(buf.write(png));
    auto run = [](const std::string& args) {
        Result r = darkroom("develop " + args + " --no-grain");
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        return r.output;
    };
    const std::string tag_warning = "says its pixels are in 'sRGB - Texture' (oiio:ColorSpace \"sRGB\")";
    const std::string integer_warning = "linear values ('lin_rec709') as integers";

    const std::string both = run(png + " -o " + tmp("colour-warn-1.png"));
    CHECK(both.find(tag_warning) != std::string::npos);
    CHECK(both.find("--iscolorspace \"sRGB - Texture\"") != std::string::npos);
    CHECK(both.find(integer_warning) != std::string::npos);
    // The named fixes silence them; a float input (OpenImageIO's "Linear", which the config does
    // not name) and a float output have nothing to warn of.
    CHECK(run(png + " -o " + tmp("colour-warn-2.png") + " --iscolorspace sRGB --ociodisplay sRGB Standard").empty());
    CHECK(run(exr + " -o " + tmp("colour-warn-3.exr")).empty());
    CHECK(run(exr + " -o " + tmp("colour-warn-4.exr") + " -d half").empty());
    // Integers that are not linear: a scan's code values, or a tag that is the working space.
    CHECK(run(exr + " -o " + tmp("colour-warn-5.png") + " --output scan").empty());
    CHECK(run(exr + " -o " + tmp("colour-warn-6.tif") + " -d uint16").find(integer_warning) != std::string::npos);
    const std::string linear_png = tmp("colour-warn-linear.png");
    spec.attribute("oiio:ColorSpace", "lin_rec709");
    OIIO::ImageBuf linear(spec);
    REQUIRE(linear.write(linear_png));
    CHECK(run(linear_png + " -o " + tmp("colour-warn-7.exr")).empty());
}
