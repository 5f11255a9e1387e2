// The darkroom program run as a user runs it: exit codes, messages, outputs.
#include <catch2/catch.hpp>
#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_support.h"

using namespace darkroom_test;

TEST_CASE("develop writes an output image", "[cli]") {
    std::string in = make_input("develop-in.exr"), out = (kTmp / "out.exr").string();
    fs::remove(out);
    Result r = darkroom("develop " + in + " -o " + out + " --film kodak-tri-x-400 -v");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.output, Catch::Contains("grain") && Catch::Contains("enlarger"));
    CHECK(pixels(out).size() == 64 * 48 * 3);
}

TEST_CASE("a reversal film develops to a slide: print with no paper, scan, and the stocks listed by role",
          "[cli][reversal]") {
    const std::string in = make_input("slide-in.exr"), print = (kTmp / "slide-print.exr").string(),
                      scan = (kTmp / "slide-scan.exr").string();
    const std::string slide = " --film fujifilm-provia-100f --no-grain";
    // The look's default paper is not used; 'none' is accepted for the print output too.
    for (const char* paper : {"", " --paper none"}) {
        fs::remove(print);
        Result r = darkroom("develop " + in + " -o " + print + slide + paper + " -v");
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        CHECK_THAT(r.output, Catch::Contains("the reversal film's spectral transmittance") &&
                                 !Catch::Contains("enlarger"));
    }
    REQUIRE(darkroom("develop " + in + " -o " + scan + slide + " --output scan").exit_code == 0);
    const std::vector<float> p = pixels(print), s = pixels(scan);
    REQUIRE(p.size() == 64 * 48 * 3);
    REQUIRE(s.size() == p.size());
    // A positive: where the slide is brighter it holds less density, so a lower scan code.
    size_t brightest = 0, darkest = 0;
    for (size_t i = 0; i < p.size(); i += 3) {
        if (p[i + 1] > p[brightest + 1]) brightest = i;
        if (p[i + 1] < p[darkest + 1]) darkest = i;
    }
    REQUIRE(p[brightest + 1] > p[darkest + 1]);
    CHECK(s[brightest + 1] < s[darkest + 1]);
    // A negative film still needs a paper for its print.
    Result r = darkroom("develop " + in + " -o " + print + " --film kodak-portra-400 --paper none");
    CHECK(r.exit_code != 0);
    CHECK_THAT(r.output, Catch::Contains("print needs a paper"));

    r = darkroom("stocks");
    REQUIRE(r.exit_code == 0);
    // By role: negatives, then reversal films, then print film, then papers.
    const size_t negative = r.output.find("  negative  "), reversal = r.output.find("fujifilm-provia-100f  reversal"),
                 print_film = r.output.find("  print-film  "), paper = r.output.find("  paper  ");
    CHECK(negative < reversal);
    CHECK(reversal < print_film);
    CHECK(print_film < paper);
    CHECK(paper != std::string::npos);
}

TEST_CASE("a window renders the same pixels as that window of the full frame", "[cli][determinism]") {
    std::string in = make_input("window-in.exr", 80, 60), full = (kTmp / "full.exr").string(),
                part = (kTmp / "part.exr").string();
    const std::string look = " --seed 5 --frame 12 --frame-width-mm 4 --print-width-mm 30";
    REQUIRE(darkroom("develop " + in + " -o " + full + look + " --threads 1").exit_code == 0);
    REQUIRE(darkroom("develop " + in + " -o " + part + look + " --threads 2 --window 17,9,40,30").exit_code == 0);
    OIIO::ImageSpec spec;
    std::vector<float> f = pixels(full), p = pixels(part, &spec);
    CHECK(spec.x == 17);
    CHECK(spec.y == 9);
    CHECK(spec.full_width == 80);
    for (int y = 0; y < 30; ++y)
        for (int x = 0; x < 40; ++x)
            for (int c = 0; c < 3; ++c) REQUIRE(p[(y * 40 + x) * 3 + c] == f[((y + 9) * 80 + x + 17) * 3 + c]);
}

TEST_CASE("bad input gets a message naming the problem and a non-zero exit", "[cli][bad-input]") {
    std::string in = make_input("bad-in.exr"), out = (kTmp / "never.exr").string();
    fs::remove(out);
    struct Case {
        std::string args, message;
    };
    for (const Case& c : std::vector<Case>{
             {"develop /nonexistent.exr -o " + out, "does not exist"},
             {"develop " + in + " -o " + out + " --film no-such-film", "unknown stock 'no-such-film'"},
             {"develop " + in + " -o " + out + " --exposure lots", "--exposure"},
             {"develop " + in + " -o " + out + " --output slide", "--output"},
             {"develop " + in + " -o " + out + " --window 60,40,10,10", "not inside"},
             {"develop " + in + " -o " + out + " --window 1,2,3", "--window"},
             {"develop " + in + " -o " + out + " --window 0,0,0,5", "has no pixels"},
             {"develop " + in + " -o " + out + " --print-exposure inf", "--print-exposure: must be a number from -64 to 64, not inf"},
             {"develop " + in + " -o " + out + " --paper none", "--output print needs a paper, and --paper is none"},
             {"develop " + in + " -o /nonexistent-dir/x.exr", "cannot write"},
             {"develop " + in + " -o " + out + " --film " + (kTmp / "missing.json").string(), "cannot open"},
             {"frobnicate", "'frobnicate' is not a command"},
             {"develop " + in + " -o " + (kTmp / "d.png").string() + " --output density", "float"},
             {"develop " + in + " -o " + (kTmp / "d.png").string() + " --output density -d float", "not '"},
             {"develop " + in + " -o " + out + " --output density -d uint16", "-d uint16"},
         }) {
        Result r = darkroom(c.args);
        INFO(c.args << "\n" << r.output);
        CHECK(r.exit_code != 0);
        CHECK_THAT(r.output, Catch::Contains(c.message));
    }
    CHECK_FALSE(fs::exists(out));
}

TEST_CASE("an unknown command or stock suggests the known names a typo away, and only those", "[cli][bad-input]") {
    const std::string in = make_input("suggest-in.exr", 16, 12), out = (kTmp / "suggest-never.exr").string();
    struct Case {
        std::string args, message;
        int exit_code;
    };
    for (const Case& c : std::vector<Case>{
             {"devlop " + in + " -o " + out, "'devlop' is not a command of darkroom: did you mean 'develop'?", 109},
             {"stock", "did you mean 'stocks'?", 109},
             {"grain analyse " + in, "'analyse' is not a command of darkroom grain: did you mean 'analyze'?", 109},
             {"develop " + in + " -o " + out + " --film kodak-vison3-250d", "did you mean 'kodak-vision3-250d'?", 1},
             {"develop " + in + " -o " + out + " --paper Kodak-2383", "did you mean 'kodak-2383'?", 1},
         }) {
        Result r = darkroom(c.args);
        INFO(c.args << "\n" << r.output);
        CHECK(r.exit_code == c.exit_code);
        CHECK_THAT(r.output, Catch::Contains("darkroom: error: ") && Catch::Contains(c.message));
    }
    for (const std::string& args : {std::string("frobnicate"), "develop " + in + " -o " + out + " --film agfa"}) {
        Result r = darkroom(args);
        INFO(args << "\n" << r.output);
        CHECK(r.exit_code != 0);
        CHECK_THAT(r.output, !Catch::Contains("did you mean"));
    }
    CHECK_FALSE(fs::exists(out));
}

TEST_CASE("develop in.exr out.exr, oiiotool's habit, is told to name the output with -o", "[cli][bad-input]") {
    const std::string in = make_input("habit-in.exr", 16, 12), out = (kTmp / "habit-out.exr").string();
    fs::remove(out);
    Result r = darkroom("develop " + in + " " + out + " --no-grain");
    INFO(r.output);
    CHECK(r.exit_code == 109);
    CHECK_THAT(r.output, Catch::Contains("'" + out + "' is a second input: name the output with -o, as in 'darkroom "
                                         "develop " + in + " -o " + out + "'"));
    CHECK_FALSE(fs::exists(out));
    // With -o given, a second name is only an argument too many.
    r = darkroom("develop " + in + " " + out + " -o " + out);
    CHECK(r.exit_code == 109);
    CHECK_THAT(r.output, !Catch::Contains("name the output with -o"));
    CHECK_FALSE(fs::exists(out));
}

TEST_CASE("every exit status is listed in --help and in the reference, and the listed ones are given", "[cli]") {
    Result help = darkroom("--help");
    REQUIRE(help.exit_code == 0);
    const size_t footer = help.output.find("Exit status:\n");
    REQUIRE(footer != std::string::npos);
    // "  104    a flag's value that does not convert (...)", one a line.
    std::map<std::string, std::string> listed;
    std::istringstream lines(help.output.substr(footer + 13));
    for (std::string line; std::getline(lines, line) && line.rfind("  ", 0) == 0;) {
        const size_t status_end = line.find(' ', 2), meaning = line.find_first_not_of(' ', status_end);
        listed[line.substr(2, status_end - 2)] = line.substr(meaning);
    }
    REQUIRE(listed.count("0") == 1);
    REQUIRE(listed.count("128+N") == 1);  // (the kill tests check the status itself)
    const std::string reference = file_bytes(fs::path(DARKROOM_SOURCE_DIR) / "docs/reference/exit-codes.md");
    for (const auto& [status, meaning] : listed) {
        INFO(status << " " << meaning);
        CHECK_THAT(reference, Catch::Contains("| " + status + " | " + meaning + " |"));
    }

    // Each status a command line gives is listed.
    const std::string in = make_input("status-in.exr", 16, 12), develop = "develop " + in + " -o " +
                                                                          (kTmp / "status-out.exr").string();
    for (const std::string& args :
         {develop, develop + " --film no-such-film", develop + " --exposure lots", develop + " --quality bogus",
          std::string(""), develop + " --tocolorspace ACEScg --ociodisplay sRGB Standard", develop + " --bogus",
          develop + " --window 1,2,3"}) {
        const int status = darkroom(args).exit_code;
        INFO(args << " -> " << status);
        CHECK(listed.count(std::to_string(status)) == 1);
    }
}

// OpenImageIO writes an unknown compression name as zip without a word: the names of the
// output's format are checked before any work (and a level only where one is taken), and
// each named one is what the file gets.
TEST_CASE("a compression is one of the output format's names and is written as given", "[cli][bad-input][metadata]") {
    const std::string in = make_input("compression-in.exr"), never = (kTmp / "never-compressed.exr").string();
    fs::remove(never);
    for (const auto& [flag, message] : std::vector<std::pair<std::string, std::string>>{
             {"bogus", "--compression 'bogus' is not one of OpenEXR's: none, rle, zip"},
             {"lzw", "is not one of OpenEXR's"},
             {"piz:3", "'piz' takes no level"},
             {"dwaa:fast", "the level after ':' must be a number above 0"},
             {"zip:", "the level after ':' must be a number above 0"}}) {
        Result r = darkroom("develop " + in + " -o " + never + " --compression " + flag);
        INFO(flag << "\n" << r.output);
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.output, Catch::Contains(message));
        CHECK_FALSE(fs::exists(never));
    }
    for (const auto& [name, flag, message] :
         {std::tuple<std::string, std::string, std::string>{"never.tif", "b44", "is not one of TIFF's"},
          {"never.png", "none", "is not one of PNG's: default, filtered, huffman, rle, fixed"},
          {"never.png", "zip:9", "is not one of PNG's"},
          {"never.png", "rle:3", "PNG takes no level"},
          {"never.jpg", "zip", "is not one of JPEG's: jpeg"},
          {"never.jpeg", "jpeg:best", "the level after ':' must be a number above 0"}}) {
        Result r = darkroom("develop " + in + " -o " + (kTmp / name).string() + " --compression " + flag);
        INFO(name << " " << flag << "\n" << r.output);
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.output, Catch::Contains(message));
        CHECK_FALSE(fs::exists(kTmp / name));
    }
    Result r;
    for (const auto& [name, flag, written] :
         {std::tuple<std::string, std::string, std::string>{"compressed.exr", "dwab:60", "dwab"},
          {"compressed.exr", "zips", "zips"},
          {"compressed.tif", "lzw", "lzw"},
          {"compressed.tif", "deflate:6", "zip"}}) {
        const std::string out = (kTmp / name).string();
        r = darkroom("develop " + in + " -o " + out + " --compression " + flag);
        INFO(flag << "\n" << r.output);
        REQUIRE(r.exit_code == 0);
        auto file = OIIO::ImageInput::open(out);
        REQUIRE(file);
        CHECK(file->spec().get_string_attribute("compression") == written);
    }
    // PNG and JPEG files do not say how they were compressed: that the name reached the
    // writer shows in the files' sizes (another zlib strategy, a lower JPEG quality).
    auto size_with = [&](const std::string& name, const std::string& flag) {
        const fs::path out = kTmp / name;
        Result written = darkroom("develop " + in + " -o " + out.string() + " --compression " + flag);
        INFO(flag << "\n" << written.output);
        REQUIRE(written.exit_code == 0);
        return fs::file_size(out);
    };
    CHECK(size_with("huffman.png", "huffman") != size_with("default.png", "default"));
    CHECK(size_with("low.jpg", "jpeg:20") < size_with("high.jpg", "jpeg:95"));
}

// A film scan's deliverable: 10-bit log DPX whose header says printing density, as a
// scanner's does (OpenImageIO reads it back as KodakLog, an alias of the config's Cineon
// Log). A DPX's transfer and colorimetric describe its pixels: a print made from such a scan
// does not keep them, and grain apply, which keeps the encoding, does.
TEST_CASE("a scan as 10-bit DPX says printing density, and a DPX's tags follow its encoding", "[cli][metadata]") {
    const std::string in = make_input("dpx-in.exr"), scan_exr = (kTmp / "scan.exr").string(),
                      scan_dpx = (kTmp / "scan.dpx").string(), print_dpx = (kTmp / "print-from-scan.dpx").string();
    REQUIRE(darkroom("develop " + in + " -o " + scan_exr + " --output scan --seed 2").exit_code == 0);
    Result r = darkroom("develop " + in + " -o " + scan_dpx + " --output scan --seed 2 -d uint10");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    OIIO::ImageSpec spec;
    const std::vector<float> code = pixels(scan_dpx, &spec), exact = pixels(scan_exr);
    CHECK(spec.get_int_attribute("oiio:BitsPerSample") == 10);
    CHECK(spec.get_string_attribute("dpx:Transfer") == "Logarithmic");
    CHECK(spec.get_string_attribute("dpx:Colorimetric") == "Printing density");
    CHECK(spec.get_string_attribute("oiio:ColorSpace") == "KodakLog");
    REQUIRE(code.size() == exact.size());
    double worst = 0;
    for (size_t i = 0; i < code.size(); ++i) worst = std::max(worst, double(std::abs(code[i] - exact[i])));
    CHECK(worst <= 1.0 / 1023);  // within a 10-bit code value (8 bits would be 4)

    // Read without --iscolorspace, the tag says what it is.
    r = darkroom("develop " + scan_dpx + " -o " + print_dpx);
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.output, Catch::Contains("give --iscolorspace \"Cineon Log\""));
    REQUIRE(darkroom("develop " + scan_dpx + " -o " + print_dpx + " --iscolorspace 'Cineon Log' --ociodisplay '' ''").exit_code == 0);
    pixels(print_dpx, &spec);
    CHECK(spec.get_string_attribute("dpx:Transfer") != "Logarithmic");
    CHECK(spec.get_string_attribute("dpx:Colorimetric") != "Printing density");

    const std::string profile = (kTmp / "dpx-grain.json").string(), grained = (kTmp / "scan-grained.dpx").string();
    REQUIRE(darkroom("grain predict --stock kodak-vision3-500t --width 2048 -o " + profile).exit_code == 0);
    REQUIRE(darkroom("grain apply " + scan_dpx + " --profile " + profile + " -o " + grained).exit_code == 0);
    pixels(grained, &spec);
    CHECK(spec.get_string_attribute("dpx:Transfer") == "Logarithmic");
    CHECK(spec.get_int_attribute("oiio:BitsPerSample") == 10);

    const std::string tiff = (kTmp / "scan-12.tif").string();
    REQUIRE(darkroom("develop " + in + " -o " + tiff + " --output scan -d uint12").exit_code == 0);
    pixels(tiff, &spec);
    CHECK(spec.get_int_attribute("oiio:BitsPerSample") == 12);
}

// With no -d, a result keeps its input's data type as oiiotool's outputs do, where the format
// stores it: a half render's print is half (a float one would be twice the file), a 16-bit
// TIFF's a 16-bit TIFF, a 10-bit DPX's a 10-bit DPX; densities stay float.
TEST_CASE("develop writes its input's data type unless -d says otherwise, and densities as float", "[cli][metadata]") {
    const std::string in = make_input("type-in.exr");
    auto input_as = [&](const std::string& name, OIIO::TypeDesc type, int bits = 0) {
        OIIO::ImageBuf buf(in);
        REQUIRE(buf.read(0, 0, true, OIIO::TypeDesc::FLOAT));
        if (bits) buf.specmod().attribute("oiio:BitsPerSample", bits);
        buf.set_write_format(type);
        const std::string path = (kTmp / name).string();
        REQUIRE(buf.write(path));
        return path;
    };
    const std::string half = input_as("type-half.exr", OIIO::TypeDesc::HALF),
                      tiff16 = input_as("type-16.tif", OIIO::TypeDesc::UINT16),
                      dpx10 = input_as("type-10.dpx", OIIO::TypeDesc::UINT16, 10);
    struct Case {
        std::string input, output, flags;
        OIIO::TypeDesc type;
        int bits;
    };
    const Case cases[] = {{half, "type-print.exr", "", OIIO::TypeDesc::HALF, 0},
                          {half, "type-print-float.exr", " -d float", OIIO::TypeDesc::FLOAT, 0},
                          {half, "type-density.exr", " --output density", OIIO::TypeDesc::FLOAT, 0},
                          {in, "type-print-from-float.exr", "", OIIO::TypeDesc::FLOAT, 0},
                          {tiff16, "type-print.tif", "", OIIO::TypeDesc::UINT16, 16},
                          {tiff16, "type-print-16.exr", "", OIIO::TypeDesc::HALF, 0},
                          {tiff16, "type-density.tif", " --output density", OIIO::TypeDesc::FLOAT, 32},
                          {dpx10, "type-print.dpx", "", OIIO::TypeDesc::UINT16, 10}};
    for (const Case& c : cases) {
        const std::string out = (kTmp / c.output).string();
        const Result r = darkroom("develop " + c.input + " -o " + out + c.flags);
        INFO(c.input << " -> " << c.output << c.flags << ": " << r.output);
        REQUIRE(r.exit_code == 0);
        auto file = OIIO::ImageInput::open(out);
        REQUIRE(file);
        CHECK(file->spec().format == c.type);
        if (c.bits) CHECK(file->spec().get_int_attribute("oiio:BitsPerSample") == c.bits);
        // Linear values in integers: said, now that the input decides the file's type, and by a
        // dry run too (from the input's header), which writes nothing.
        const bool integers = c.output == "type-print.tif" || c.output == "type-print.dpx";
        CHECK((r.output.find("as integers") != std::string::npos) == integers);
        const std::string dry_out = (kTmp / ("dry-" + c.output)).string();
        const Result dry = darkroom("develop " + c.input + " -o " + dry_out + c.flags + " -n");
        INFO("dry run: " << dry.output);
        CHECK(dry.exit_code == 0);
        CHECK((dry.output.find("as integers") != std::string::npos) == integers);
        CHECK_FALSE(fs::exists(dry_out));
    }
}

// An output that cannot be written is found before any frame is read or developed (a frame's
// failure is reported as "frame N ... failed"), so a farm job fails at once, not after a frame.
TEST_CASE("an unwritable output is refused before any frame is developed", "[cli][bad-input]") {
    const std::string in = make_input("unwritable-in.exr");
    for (const auto& [output, message] : {std::pair<std::string, std::string>{"/nonexistent-dir/x.exr", "the folder '/nonexistent-dir' does not exist"},
                                          {(kTmp / "x.no-such-format").string(), "could not find a format writer"}}) {
        Result r = darkroom("develop " + in + " -o " + output);
        INFO(r.output);
        CHECK(r.exit_code == 1);
        CHECK_THAT(r.output, Catch::Contains(message));
        CHECK_THAT(r.output, !Catch::Contains("frame 0"));
        CHECK_FALSE(fs::exists(output));
    }
}

TEST_CASE("a corrupt image and a bad stock file are reported, and leave no output", "[cli][bad-input]") {
    std::string bad_image = (kTmp / "corrupt.exr").string(), bad_stock = (kTmp / "bad-stock.json").string();
    std::ofstream(bad_image) << "this is not an EXR file";
    std::ofstream(bad_stock) << R"({"format": "darkroom-stock", "version": 1, "id": "x", "name": "x", "kind": "negative"})";
    std::string out = (kTmp / "never2.exr").string();
    fs::remove(out);
    Result r = darkroom("develop " + bad_image + " -o " + out);
    CHECK(r.exit_code != 0);
    CHECK_THAT(r.output, Catch::Contains("corrupt.exr"));
    r = darkroom("develop " + make_input("corrupt-test-in.exr") + " -o " + out + " --film " + bad_stock);
    CHECK(r.exit_code != 0);
    CHECK_THAT(r.output, Catch::Contains("bad-stock.json: field 'iso_speed': missing"));
    CHECK_FALSE(fs::exists(out));
    for (auto& entry : fs::directory_iterator(kTmp))
        CHECK(entry.path().filename().string().rfind(".darkroom-tmp", 0) == std::string::npos);
}

TEST_CASE("stocks lists the presets and demo renders without an input", "[cli]") {
    Result r = darkroom("stocks --json");
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.output, Catch::Contains("kodak-tri-x-400") && Catch::Contains("\"kind\": \"paper\""));
    // Listed by role: every negative before every print film, every print film before every paper.
    r = darkroom("stocks");
    REQUIRE(r.exit_code == 0);
    const size_t last_negative = r.output.rfind("  negative  "), first_print_film = r.output.find("  print-film  "),
                 last_print_film = r.output.rfind("  print-film  "), first_paper = r.output.find("  paper  ");
    REQUIRE(first_print_film != std::string::npos);
    CHECK(last_negative < first_print_film);
    CHECK(last_print_film < first_paper);
    CHECK_THAT(r.output, Catch::Contains("kodak-portra-800-push2  negative  ISO 3200") &&
                             Catch::Contains("kodak-2393  print-film") && Catch::Contains("kodak-supra-endura  paper"));
    fs::path dir = kTmp / "demo";
    fs::remove_all(dir);
    r = darkroom("demo -o " + dir.string());
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    for (const char* f : {"scene.exr", "print.exr", "print.png", "negative.png"}) CHECK(fs::exists(dir / f));
}

// ---- darkroom grain: plate matching ----

namespace {

// Flat 64 px patches of Cineon-range levels, no grain.
std::string make_patches(const std::string& name, int size = 256) {
    fs::create_directories(kTmp);
    std::string path = (kTmp / name).string();
    OIIO::ImageBuf buf(OIIO::ImageSpec(size, size, 3, OIIO::TypeDesc::FLOAT));
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            float level = 0.15f + 0.1f * float(((x / 64) + 4 * (y / 64)) % 7);
            const float rgb[3] = {level, level * 0.9f + 0.05f, level * 0.8f + 0.1f};
            buf.setpixel(x, y, rgb);
        }
    REQUIRE(buf.write(path));
    return path;
}

nlohmann::json read_json(const std::string& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in);
}

// Linear interpolation of a profile channel's response curve.
double sigma_at(const nlohmann::json& channel, double level) {
    std::vector<double> l = channel["response"]["level"], s = channel["response"]["sigma"];
    if (level <= l.front()) return s.front();
    for (size_t i = 1; i < l.size(); ++i)
        if (level <= l[i]) return s[i - 1] + (s[i] - s[i - 1]) * (level - l[i - 1]) / (l[i] - l[i - 1]);
    return s.back();
}

}  // namespace

TEST_CASE("grain predict, apply, analyze and compare: a plate's grain carried onto a clean image", "[cli][grain]") {
    std::string plate;
    const std::string clean = make_patches("grain-clean.exr"), predicted = (kTmp / "predicted.json").string(),
                      measured = (kTmp / "measured.json").string(),
                      cg = (kTmp / "grain-cg.exr").string(), chart = (kTmp / "grain-chart.svg").string();
    Result r = darkroom("grain predict --stock kodak-tri-x-400 --width 2048 -o " + predicted);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.output, Catch::Contains("kodak-tri-x-400 scanned at 2048 px"));
    // A two-frame plate sequence: frames 1 and 2 of the same grain.
    const std::string sequence = (kTmp / "grain-plate.####.exr").string();
    for (const char* frame : {"1", "2"})
        REQUIRE(darkroom("grain apply --iscolorspace \"Cineon log\" " + clean + " --profile " + predicted + " -o " + (kTmp / "grain-plate.000").string() +
                         frame + ".exr --seed 1 --frame " + frame)
                    .exit_code == 0);
    plate = (kTmp / "grain-plate.0001.exr").string();
    const std::string png_chart = (kTmp / "grain-analysis.png").string();
    r = darkroom("grain analyze " + sequence + " --frames 1-2 --iscolorspace 'Cineon log' -o " + measured +
                 " --plot " + png_chart);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    OIIO::ImageSpec chart_spec;
    pixels(png_chart, &chart_spec);
    CHECK(chart_spec.width == 1280);
    nlohmann::json profile = read_json(measured);
    CHECK(profile["encoding"] == "log");
    CHECK(profile["colorspace"] == "Cineon log");
    CHECK(profile["channel_correlation"][0][1] > 0.95);  // a black-and-white stock: the same grain in R, G, B
    REQUIRE(darkroom("grain apply " + clean + " --profile " + measured + " -o " + cg + " --seed 2 --iscolorspace 'Cineon log'")
                .exit_code == 0);
    r = darkroom("grain compare " + plate + " " + cg + " --plot " + chart);
    INFO(r.output);
    CHECK(r.exit_code == 0);
    CHECK_THAT(r.output, Catch::Contains("grain matches"));
    std::ifstream svg(chart);
    std::stringstream text;
    text << svg.rdbuf();
    CHECK_THAT(text.str(), Catch::Contains("<svg") && Catch::Contains("R A") && Catch::Contains("R B"));

    // Twice the grain does not match: exit 4.
    const std::string doubled = (kTmp / "doubled.json").string();
    nlohmann::json twice = profile;
    for (auto& ch : twice["channels"])
        for (auto& s : ch["response"]["sigma"]) s = 2 * s.get<double>();
    std::ofstream(doubled) << twice.dump();
    r = darkroom("grain compare " + measured + " " + doubled);
    CHECK(r.exit_code == 4);
    CHECK_THAT(r.output, Catch::Contains("grain does not match"));
}

// A CG element with alpha gets grain on its light, not on its light times coverage: the
// premultiplied element's grain is the straight one's times alpha, so a transparent pixel gets
// none to add over the plate.
TEST_CASE("grain apply to premultiplied colour grains the light and keeps the coverage", "[cli][grain]") {
    const std::string straight = make_patches("grain-alpha-straight.exr", 128), profile = (kTmp / "alpha-profile.json").string(),
                      element = (kTmp / "grain-alpha-element.exr").string();
    REQUIRE(darkroom("grain predict --stock kodak-vision3-500t --width 2048 -o " + profile).exit_code == 0);
    auto alpha_at = [](int x, int y) { return float((x / 16 + y / 16) % 5) / 4.0f; };  // 0 to 1 in steps
    OIIO::ImageSpec spec;
    std::vector<float> rgb = pixels(straight, &spec);
    OIIO::ImageBuf buf(OIIO::ImageSpec(spec.width, spec.height, 4, OIIO::TypeDesc::FLOAT));
    for (OIIO::ImageBuf::Iterator<float> p(buf); !p.done(); ++p) {
        const size_t i = (size_t(p.y()) * spec.width + p.x()) * 3;
        const float a = alpha_at(p.x(), p.y());
        for (int c = 0; c < 3; ++c) p[c] = rgb[i + c] * a;
        p[3] = a;
    }
    REQUIRE(buf.write(element));
    const std::string grained_straight = (kTmp / "grain-alpha-straight-out.exr").string(),
                      grained_element = (kTmp / "grain-alpha-element-out.exr").string();
    for (const auto& [in, out] : {std::pair{straight, grained_straight}, std::pair{element, grained_element}}) {
        Result r = darkroom("grain apply --iscolorspace \"Cineon log\" " + in + " --profile " + profile + " -o " + out + " --seed 4");
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
    }
    const std::vector<float> s = pixels(grained_straight), e = pixels(grained_element);
    REQUIRE(e.size() == s.size() / 3 * 4);
    long transparent = 0;
    for (int y = 0; y < spec.height; ++y)
        for (int x = 0; x < spec.width; ++x) {
            const size_t i = size_t(y) * spec.width + x;
            const float a = alpha_at(x, y);
            REQUIRE(e[i * 4 + 3] == a);
            for (int c = 0; c < 3; ++c) REQUIRE(e[i * 4 + c] == Approx(s[i * 3 + c] * a).epsilon(1e-5).margin(1e-7));
            transparent += a == 0 && e[i * 4] == 0 && s[i * 3] != rgb[i * 3];  // grain in the straight one, none here
        }
    CHECK(transparent > 1000);
}

// A grey plate's grain goes on a grey element under the element's own channel name (it was
// renamed R): grain apply writes the channels it read.
TEST_CASE("grain apply to a grey plate keeps its channel", "[cli][grain][metadata]") {
    const std::string clean = make_patches("grain-grey-clean-rgb.exr"), rgb_profile = (kTmp / "grey-rgb.json").string(),
                      grained_rgb = (kTmp / "grain-grey-grained-rgb.exr").string();
    REQUIRE(darkroom("grain predict --stock kodak-vision3-500t --width 2048 -o " + rgb_profile).exit_code == 0);
    REQUIRE(darkroom("grain apply --iscolorspace \"Cineon log\" " + clean + " --profile " + rgb_profile + " -o " + grained_rgb + " --seed 3")
                .exit_code == 0);
    auto grey_of = [](const std::string& from, const std::string& name) {
        OIIO::ImageBuf grey = OIIO::ImageBufAlgo::channels(OIIO::ImageBuf(from), 1, {0}, {}, {"Y"});
        const std::string path = (kTmp / name).string();
        REQUIRE(grey.write(path));
        return path;
    };
    const std::string grey_plate = grey_of(grained_rgb, "grain-grey-plate.exr"),
                      grey_clean = grey_of(clean, "grain-grey-clean.exr");
    const std::string profile = (kTmp / "grey.json").string(), out = (kTmp / "grain-grey-out.exr").string();
    Result r = darkroom("grain analyze " + grey_plate + " -o " + profile);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    REQUIRE(darkroom("grain apply " + grey_clean + " --profile " + profile + " -o " + out).exit_code == 0);
    OIIO::ImageSpec spec;
    const std::vector<float> before = pixels(grey_clean), after = pixels(out, &spec);
    CHECK(spec.channelnames == std::vector<std::string>{"Y"});
    CHECK(after != before);  // grained
}

// Only the colour channels carry grain: a plate's depth is neither analysed (an RGB plate
// with Z gives the RGB plate's profile, a grey one with Z the grey one's) nor grained; a grey
// profile grains each channel of a colour result; a profile of other channels is refused.
TEST_CASE("grain analyze and apply take a plate's colour channels, not its depth", "[cli][grain]") {
    const std::string clean = make_patches("grain-depth-clean.exr"), rgb_profile = (kTmp / "depth-rgb.json").string(),
                      rgb_plate = (kTmp / "grain-depth-plate.exr").string();
    REQUIRE(darkroom("grain predict --stock kodak-vision3-500t --width 2048 -o " + rgb_profile).exit_code == 0);
    REQUIRE(darkroom("grain apply --iscolorspace \"Cineon log\" " + clean + " --profile " + rgb_profile + " -o " + rgb_plate + " --seed 8").exit_code == 0);
    // The plate's channels, with a depth ramp appended as Z.
    auto with_depth = [](const std::string& from, std::vector<int> channels, std::vector<std::string> names,
                         const std::string& name) {
        OIIO::ImageBuf colour = OIIO::ImageBufAlgo::channels(OIIO::ImageBuf(from), int(channels.size()), channels, {}, names);
        OIIO::ImageBuf depth(OIIO::ImageSpec(colour.spec().width, colour.spec().height, 1, OIIO::TypeDesc::FLOAT));
        OIIO::ImageBufAlgo::fill(depth, {1.0f}, {1e4f}, {1.0f}, {1e4f});
        depth.specmod().channelnames = {"Z"};
        const std::string plain = (kTmp / ("plain-" + name)).string(), deep = (kTmp / name).string();
        REQUIRE(colour.write(plain));
        REQUIRE(OIIO::ImageBufAlgo::channel_append(colour, depth).write(deep));
        return std::make_pair(plain, deep);
    };
    auto channels_of = [](const std::string& profile) {
        std::ifstream f(profile);
        return nlohmann::json::parse(f)["channels"];
    };
    for (const auto& [channels, names] :
         {std::make_pair(std::vector<int>{0, 1, 2}, std::vector<std::string>{"R", "G", "B"}),
          std::make_pair(std::vector<int>{1}, std::vector<std::string>{"Y"})}) {
        const auto [plain, deep] = with_depth(rgb_plate, channels, names, "grain-depth-" + names[0] + ".exr");
        const std::string plain_profile = plain + ".json", deep_profile = deep + ".json";
        REQUIRE(darkroom("grain analyze " + plain + " -o " + plain_profile).exit_code == 0);
        Result r = darkroom("grain analyze " + deep + " -o " + deep_profile);
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        CHECK(channels_of(deep_profile).size() == names.size());
        CHECK(channels_of(deep_profile) == channels_of(plain_profile));
    }

    // A colour profile on a grey element: refused, naming the profile; nothing written.
    const std::string grey_element = with_depth(clean, {1}, {"Y"}, "grain-depth-grey-element.exr").second,
                      never = (kTmp / "never-grained.exr").string();
    fs::remove(never);
    Result r = darkroom("grain apply --iscolorspace 'Cineon log' " + grey_element + " --profile " + rgb_profile + " -o " + never);
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains(rgb_profile) && Catch::Contains("1 colour channel"));
    CHECK_FALSE(fs::exists(never));
    // A grey profile on it grains Y alone, its depth untouched.
    const std::string grey_profile = (kTmp / "grain-depth-Y.exr.json").string(), grained = (kTmp / "grain-depth-grey-out.exr").string();
    REQUIRE(darkroom("grain apply " + grey_element + " --profile " + grey_profile + " -o " + grained).exit_code == 0);
    const std::vector<float> before = pixels(grey_element), after = pixels(grained);
    REQUIRE(after.size() == before.size());
    size_t grained_y = 0;
    for (size_t i = 0; i < after.size(); i += 2) {
        grained_y += after[i] != before[i];
        REQUIRE(after[i + 1] == before[i + 1]);
    }
    CHECK(grained_y > before.size() / 4);
    // And on the program's RGB print, on each of its channels (not the first alone).
    const std::string in = make_input("grain-depth-develop.exr"), print = (kTmp / "grain-depth-print.exr").string(),
                      print_grained = (kTmp / "grain-depth-print-grained.exr").string();
    REQUIRE(darkroom("develop " + in + " -o " + print + " --no-grain").exit_code == 0);
    REQUIRE(darkroom("develop " + in + " -o " + print_grained + " --grain-profile " + grey_profile).exit_code == 0);
    const std::vector<float> plain_print = pixels(print), grained_print = pixels(print_grained);
    REQUIRE(plain_print.size() == grained_print.size());
    size_t changed[3] = {0, 0, 0};
    for (size_t i = 0; i < plain_print.size(); ++i) changed[i % 3] += plain_print[i] != grained_print[i];
    for (size_t c : changed) CHECK(c > plain_print.size() / 3 / 2);
}

// A CG element's sequence takes its plate grain in one run, each frame keyed by its own
// number (as `--frame N` gives a single image, bit for bit), so the grain moves from frame
// to frame; a still with an output sequence gets moving grain; the batch flags of develop
// hold (a dry run writes nothing, --frame is for a single image, a missing frame is named).
TEST_CASE("grain apply runs a sequence, each frame with its own grain", "[cli][grain][batch]") {
    const fs::path dir = kTmp / "grain-apply-sequence";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string clean = make_patches("grain-apply-sequence-clean.exr", 96), profile = (dir / "grain.json").string();
    REQUIRE(darkroom("grain predict --stock kodak-vision3-500t --width 2048 -o " + profile).exit_code == 0);
    for (int frame : {1001, 1002, 1003}) fs::copy_file(clean, dir / ("cg." + std::to_string(frame) + ".exr"));
    const std::string look = " --profile " + profile + " --seed 4 --iscolorspace 'Cineon log'";
    Result r = darkroom("grain apply " + (dir / "cg.####.exr").string() + " -o " + (dir / "out.####.exr").string() + look +
                        " -n");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK_FALSE(fs::exists(dir / "out.1001.exr"));
    r = darkroom("grain apply " + (dir / "cg.####.exr").string() + " -o " + (dir / "out.####.exr").string() + look +
                 " --frame 3");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("--frame is for a single image"));
    r = darkroom("grain apply " + (dir / "cg.####.exr").string() + " -o " + (dir / "out.####.exr").string() + look +
                 " -q --threads 2");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    // A still through an output sequence: the same grain as the sequence's frames.
    REQUIRE(darkroom("grain apply " + clean + " -o " + (dir / "still.####.exr").string() + " --frames 1001-1003" + look +
                     " -q")
                .exit_code == 0);
    std::vector<std::vector<float>> frames;
    for (int frame : {1001, 1002, 1003}) {
        const std::string single = (dir / ("single." + std::to_string(frame) + ".exr")).string();
        REQUIRE(darkroom("grain apply " + clean + " -o " + single + look + " --frame " + std::to_string(frame)).exit_code == 0);
        const std::vector<float> out = pixels((dir / ("out." + std::to_string(frame) + ".exr")).string());
        CHECK(out == pixels(single));
        CHECK(out == pixels((dir / ("still." + std::to_string(frame) + ".exr")).string()));
        frames.push_back(out);
    }
    CHECK(frames[0] != frames[1]);
    CHECK(frames[1] != frames[2]);
    CHECK(frames[0] != pixels(clean));
    r = darkroom("grain apply " + (dir / "cg.####.exr").string() + " -o " + (dir / "out.####.exr").string() + look +
                 " --frames 1003-1004 -q");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("frame 1004") && Catch::Contains("does not exist"));
    // The element's data type is kept (a half render stays half) unless -d says otherwise.
    const std::string half = (dir / "half.exr").string();
    REQUIRE(OIIO::ImageBuf(clean).write(half, OIIO::TypeDesc::HALF));
    for (const auto& [flag, type] : {std::pair<std::string, OIIO::TypeDesc>{"", OIIO::TypeDesc::HALF},
                                     {" -d float", OIIO::TypeDesc::FLOAT}}) {
        const std::string out = (dir / "half-grained.exr").string();
        REQUIRE(darkroom("grain apply " + half + " -o " + out + look + flag).exit_code == 0);
        auto file = OIIO::ImageInput::open(out);
        REQUIRE(file);
        CHECK(file->spec().format == type);
    }
}

// Without --encoding or --iscolorspace, the plate's own tag decides its encoding: a log DPX
// scan (OpenImageIO's "KodakLog") is log, where an untagged integer file is display.
TEST_CASE("grain analyze takes a plate's encoding from its colour-space tag", "[cli][grain]") {
    const std::string clean = make_patches("grain-tag-clean.exr"), profile = (kTmp / "tag-profile.json").string(),
                      grained = (kTmp / "grain-tag-plate.exr").string();
    REQUIRE(darkroom("grain predict --stock kodak-vision3-500t --width 2048 -o " + profile).exit_code == 0);
    REQUIRE(darkroom("grain apply --iscolorspace \"Cineon log\" " + clean + " --profile " + profile + " -o " + grained + " --seed 6").exit_code == 0);
    auto analysed_encoding = [&](const std::string& name, const std::string& tag) {
        OIIO::ImageBuf plate(grained);
        REQUIRE(plate.read(0, 0, true, OIIO::TypeDesc::FLOAT));
        const std::string path = (kTmp / name).string();
        if (!tag.empty()) plate.specmod().attribute("oiio:ColorSpace", tag);
        plate.set_write_format(OIIO::TypeDesc::UINT16);
        REQUIRE(plate.write(path));
        const std::string measured = path + ".json";
        Result r = darkroom("grain analyze " + path + " -o " + measured);
        INFO(r.output);
        REQUIRE(r.exit_code == 0);
        return read_json(measured)["encoding"].get<std::string>();
    };
    CHECK(analysed_encoding("grain-tag-log.dpx", "KodakLog") == "log");
    CHECK(analysed_encoding("grain-tag-untagged.tif", "") == "display");
}

TEST_CASE("grain apply to a window of the frame gives that window of the full frame", "[cli][grain][determinism]") {
    const std::string clean = make_patches("grain-window-clean.exr"), profile = (kTmp / "window-profile.json").string(),
                      crop = (kTmp / "grain-window-crop.exr").string(), full = (kTmp / "grain-window-full.exr").string(),
                      part = (kTmp / "grain-window-part.exr").string();
    REQUIRE(darkroom("grain predict --stock kodak-tri-x-400 --width 4096 -o " + profile).exit_code == 0);
    OIIO::ImageBuf cropped = OIIO::ImageBufAlgo::cut(OIIO::ImageBuf(clean), OIIO::ROI(40, 140, 30, 130));
    cropped.specmod().x = 40;  // keep the crop's place in the frame
    cropped.specmod().y = 30;
    REQUIRE(cropped.write(crop));
    REQUIRE(darkroom("grain apply --iscolorspace \"Cineon log\" " + clean + " --profile " + profile + " -o " + full + " --threads 1").exit_code == 0);
    REQUIRE(darkroom("grain apply --iscolorspace \"Cineon log\" " + crop + " --profile " + profile + " -o " + part + " --threads 3").exit_code == 0);
    std::vector<float> f = pixels(full), p = pixels(part);
    for (int y = 0; y < 100; ++y)
        for (int x = 0; x < 100; ++x)
            for (int c = 0; c < 3; ++c) REQUIRE(p[(y * 100 + x) * 3 + c] == f[((y + 30) * 256 + x + 40) * 3 + c]);
}

TEST_CASE("grain: bad plates and profiles get a message naming the problem", "[cli][grain][bad-input]") {
    const std::string corrupt = (kTmp / "corrupt-profile.json").string(), out = (kTmp / "never-grain.exr").string();
    std::ofstream(corrupt) << R"({"format": "darkroom-grain-profile", "version": 1, "encoding": "log", "channels": []})";
    fs::remove(out);
    Result r = darkroom("grain apply " + make_patches("grain-bad-clean.exr") + " --profile " + corrupt + " -o " + out);
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("corrupt-profile.json: field 'channels'"));
    CHECK_FALSE(fs::exists(out));

    r = darkroom("grain analyze " + make_input("grain-tiny.exr", 24, 20) + " -o " + (kTmp / "never.json").string());
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("too small") && Catch::Contains("24x20"));
    CHECK_FALSE(fs::exists(kTmp / "never.json"));

    r = darkroom("grain analyze " + make_patches("grain-flat-clean.exr") + " -o " + (kTmp / "never.json").string());
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("channel R: no grain"));

    r = darkroom("grain analyze plate.####.exr -o " + (kTmp / "never.json").string());
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("--frames"));
}

TEST_CASE("grain analyze on real film scans finds grain of a few code values", "[cli][grain][reference]") {
    const fs::path plate = fs::path(DARKROOM_REFERENCE_DATA) / "plates" / "kodim23.png";
    if (!fs::exists(plate)) {
        WARN("reference plate " << plate << " not found: skipped");
        return;
    }
    const std::string profile_path = (kTmp / "kodim23.json").string(), chart = (kTmp / "kodim23.png").string();
    Result r = darkroom("grain analyze " + plate.string() + " --iscolorspace sRGB --block-size 16 -o " + profile_path +
                        " --plot " + chart);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    // The reference data's README: Photo CD grain is "about 2-4 code values of 255" (high-pass
    // std in flat areas) with the chroma smoothed, so the channels are strongly correlated.
    nlohmann::json p = read_json(profile_path);
    CHECK(p["encoding"] == "display");
    for (const auto& ch : p["channels"]) {
        double mid = sigma_at(ch, 0.5) * 255;
        CHECK(mid > 1.0);
        CHECK(mid < 5.0);
    }
    CHECK(p["channel_correlation"][0][1] > 0.5);
    CHECK(p["channel_correlation"][1][2] > 0.5);
    OIIO::ImageSpec spec;
    pixels(chart, &spec);
    CHECK(spec.width == 1280);
}

TEST_CASE("develop --grain-profile adds the plate's grain as grain apply does, in place of the stock's", "[cli][grain]") {
    const std::string clean = make_patches("profile-clean.exr"), profile = (kTmp / "profile-500t.json").string(),
                      applied = (kTmp / "profile-applied.exr").string(), developed = (kTmp / "profile-developed.exr").string();
    REQUIRE(darkroom("grain predict --stock kodak-vision3-500t --width 2048 -o " + profile).exit_code == 0);
    // A Cineon-log profile on develop's linear output is refused, naming both and the flag.
    Result refused = darkroom("develop " + clean + " -o " + developed + " --output texture --grain-profile " + profile);
    CHECK(refused.exit_code == 1);
    CHECK_THAT(refused.output, Catch::Contains("measured in log (Cineon log), the output is linear") &&
                                   Catch::Contains("--tocolorspace"));
    // As if measured on linear plates, as develop's texture output is.
    nlohmann::json linear = read_json(profile);
    linear["encoding"] = "linear";
    linear["colorspace"] = "";
    std::ofstream(profile) << linear.dump();
    REQUIRE(darkroom("grain apply " + clean + " --profile " + profile + " -o " + applied + " --seed 4 --frame 7").exit_code == 0);
    // Texture output without MTF and halation is the input itself, so only the plate's grain remains.
    Result r = darkroom("develop " + clean + " -o " + developed + " --film kodak-vision3-500t --output texture --no-mtf " +
                        "--halation 0 --grain-profile " + profile + " --seed 4 --frame 7 -v");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.output, Catch::Contains("replaces the stock's grain"));
    std::vector<float> a = pixels(applied), d = pixels(developed), c = pixels(clean);
    REQUIRE(a.size() == d.size());
    double grain = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        REQUIRE(d[i] == Approx(a[i]).margin(1e-6));
        grain = std::max(grain, double(std::abs(a[i] - c[i])));
    }
    CHECK(grain > 1e-3);
    r = darkroom("develop " + clean + " -o " + developed + " --grain-profile /nonexistent.json --output texture");
    CHECK(r.exit_code != 0);
    CHECK_THAT(r.output, Catch::Contains("/nonexistent.json"));
}

TEST_CASE("plot draws a stock's curves, sensitivities, dyes and MTF", "[cli][plot]") {
    const std::string svg = (kTmp / "plot-500t.svg").string(), png = (kTmp / "plot-500t.png").string();
    Result r = darkroom("plot kodak-vision3-500t -o " + svg);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    const std::string text = file_bytes(svg);
    for (const char* expected : {"characteristic curves", "spectral sensitivity", "spectral dye density",
                                 "modulation transfer", "red", "green", "blue", "base + fog"})
        CHECK_THAT(text, Catch::Contains(expected));
    REQUIRE(darkroom("plot kodak-tri-x-400 -o " + png).exit_code == 0);
    OIIO::ImageSpec spec;
    const size_t values = pixels(png, &spec).size();
    CHECK(values == size_t(spec.width) * spec.height * spec.nchannels);
    CHECK(spec.width > 2 * spec.height);  // four panels side by side
    r = darkroom("plot no-such-stock -o " + svg);
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("unknown stock 'no-such-stock'"));
}

TEST_CASE("bake-lut reads a whole look file and offers only the settings a LUT holds", "[cli][look]") {
    const std::string look = (kTmp / "whole-look.json").string(), lut = (kTmp / "whole-look.cube").string();
    REQUIRE(darkroom("develop --film kodak-portra-400 --paper kodak-portra-endura --seed 9 --grain-amount 2 "
                     "--halation 0.5 --save-look " + look).exit_code == 0);
    fs::remove(lut);
    Result baked = darkroom("bake-lut --look " + look + " --size 9 -o " + lut);
    INFO(baked.output);
    CHECK(baked.exit_code == 0);
    CHECK(fs::exists(lut));
    // Grain, seed and optics cannot change a LUT, so bake-lut has no flags for them.
    const std::string help = darkroom("bake-lut --help").output;
    for (const char* flag : {"--seed", "--grain-amount", "--halation", "--no-mtf", "--frame-width-mm"}) {
        INFO(flag);
        CHECK(help.find(std::string(flag) + " ") == std::string::npos);
    }
    CHECK(help.find("--print-exposure") != std::string::npos);
    CHECK(darkroom("bake-lut --seed 3 -o " + lut).exit_code != 0);
}

TEST_CASE("sensitometry --print-greys measures each pair's printed grey scale, neutral at mid grey", "[cli][viewing]") {
    Result r = darkroom("sensitometry --print-greys --film kodak-vision3-250d --json");
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    const nlohmann::json pairs = nlohmann::json::parse(r.output);
    const nlohmann::json stocks = nlohmann::json::parse(darkroom("stocks --json").output);
    size_t papers = 0;
    for (const auto& s : stocks) papers += s["kind"] == "paper" || s["kind"] == "print-film";
    REQUIRE(pairs.size() == papers);
    for (const auto& pair : pairs) {
        INFO(pair.dump());
        CHECK(pair["film"] == "kodak-vision3-250d");
        REQUIRE(pair["ev"] == nlohmann::json({-3, -2, -1, 0, 1, 2, 3}));
        CHECK(pair["chroma"][3].get<double>() < 1e-4);  // the automatic lights' grey
        double worst = 0;
        for (int i = 1; i <= 5; ++i) worst = std::max(worst, pair["chroma"][i].get<double>());
        CHECK(pair["max_chroma_within_2_ev"].get<double>() == worst);
    }
    // The table for the docs: a header, a rule and one row a pair.
    r = darkroom("sensitometry --print-greys --paper kodak-2383 --print-viewing absolute");
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.output, Catch::StartsWith("| film | paper | -3 EV") && Catch::Contains("| kodak-vision3-500t | kodak-2383 |"));
    r = darkroom("sensitometry --print-greys --print-viewing sideways");
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.output, Catch::Contains("--print-viewing must be one of media-relative, absolute"));
}
