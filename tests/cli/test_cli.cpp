// The darkroom program run as a user runs it: exit codes, messages, outputs.
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
             {"develop " + in + " -o " + out + " --paper none", "--paper none"},
             {"develop " + in + " -o /nonexistent-dir/x.exr", "cannot write"},
             {"develop " + in + " -o " + out + " --film " + (kTmp / "missing.json").string(), "cannot open"},
             {"frobnicate", "subcommand is required"},
             {"develop " + in + " -o " + (kTmp / "d.png").string() + " --output density", "float"},
         }) {
        Result r = darkroom(c.args);
        INFO(c.args << "\n" << r.output);
        CHECK(r.exit_code != 0);
        CHECK_THAT(r.output, Catch::Contains(c.message));
    }
    CHECK_FALSE(fs::exists(out));
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
    fs::path dir = kTmp / "demo";
    fs::remove_all(dir);
    r = darkroom("demo -o " + dir.string());
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    for (const char* f : {"scene.exr", "print.exr", "print.png", "negative.png"}) CHECK(fs::exists(dir / f));
}
