#include <catch2/catch.hpp>

#include "core/did_you_mean.h"
#include "core/stock.h"
#include "test_support.h"

using namespace darkroom;

TEST_CASE("a stock file parses and round-trips through JSON", "[stock]") {
    Stock s = test::test_film();
    CHECK(s.id == "test-film");
    REQUIRE(s.layers.size() == 1);
    Stock again = parse_stock_json(stock_to_json(s), "round trip");
    CHECK(again.iso_speed == s.iso_speed);
    CHECK(again.layers[0].density_curve.y == s.layers[0].density_curve.y);
    CHECK(again.layers[0].grain.rms_granularity == s.layers[0].grain.rms_granularity);
}

TEST_CASE("bad stock files name the file, the field and the problem", "[stock]") {
    auto error_of = [](const std::string& json) { return test::stock_error_of(json, "my.json"); };
    const std::string good = test::test_film_json();
    auto replace = [&](const std::string& from, const std::string& to) { return test::replaced(good, from, to); };
    CHECK_THAT(error_of("{not json"), Catch::Contains("my.json") && Catch::Contains("not valid JSON"));
    // A number too large for a double is nlohmann-json's out_of_range, not a parse_error (found by fuzzing).
    CHECK_THAT(error_of(replace("\"iso_speed\": 200", "\"iso_speed\": 1e999")),
               Catch::Contains("my.json") && Catch::Contains("not valid JSON"));
    // A value nested 200000 deep where a string belongs: named by its kind, not dumped (dumping
    // recursed once per level and overflowed the stack; found by fuzzing).
    const std::string deep = std::string(200000, '[') + std::string(200000, ']');
    CHECK_THAT(error_of(replace("\"kind\": \"negative\"", "\"kind\": " + deep)),
               Catch::Contains("field 'kind': expected a string, got an array of size 1"));
    CHECK_THAT(error_of(replace("\"iso_speed\": 200", "\"iso_speed\": \"fast\"")),
               Catch::Contains("my.json: field 'iso_speed': expected a number"));
    CHECK_THAT(error_of(replace("\"iso_speed\": 200", "\"iso_speed\": -5")),
               Catch::Contains("field 'iso_speed'") && Catch::Contains("outside"));
    CHECK_THAT(error_of(replace("\"rms_granularity\": 0.012, ", "")),
               Catch::Contains("field 'layers[0].grain.rms_granularity': missing"));
    CHECK_THAT(error_of(replace("\"version\": 1", "\"version\": 7")),
               Catch::Contains("field 'version'") && Catch::Contains("not supported"));
    CHECK_THAT(error_of(replace("panchromatic", "infrared")),
               Catch::Contains("layers[0].spectral_sensitivity.emulsion") && Catch::Contains("unknown emulsion"));
    CHECK_THAT(error_of(replace("\"response\": [1.0, 0.97", "\"response\": [1.0")),
               Catch::Contains("layers[0].mtf") && Catch::Contains("7 values but 'response' has 6"));
    CHECK_THAT(error_of(replace("\"d_max\": 2.6", "\"d_max\": 0.3")),
               Catch::Contains("layers[0].density_curve.parametric.d_max"));
    // A sharp toe under a broad shoulder: the shoulder's softplus bends down before the toe
    // rises, so the formula's density falls below the toe (found by fuzzing: it was accepted,
    // then its written table was refused).
    CHECK_THAT(error_of(replace("\"toe\": 0.12, \"shoulder\": 0.2", "\"toe\": 0.001, \"shoulder\": 0.5")),
               Catch::Contains("field 'layers[0].density_curve.parametric': the curve falls at log H") &&
                   Catch::Contains("density must not decrease with exposure"));
    CHECK_THAT(error_of(replace("\"kind\": \"negative\"", "\"kind\": \"slide\"")),
               Catch::Contains("field 'kind'") && Catch::Contains("unknown kind"));
}

TEST_CASE("a reversal film's curve must fall with exposure, and only a falling form describes it", "[stock]") {
    auto error_of = [](const std::string& json) { return test::stock_error_of(json, "slide.json"); };
    const std::string parametric = R"({"parametric": {"gamma": 0.65, "d_min": 0.25, "d_max": 2.6, "toe": 0.12, "shoulder": 0.2}})";
    const std::string reversal = test::replaced(test::test_film_json(), "\"kind\": \"negative\"", "\"kind\": \"reversal\"");
    auto with_curve = [&](const std::string& stock, const std::string& curve) { return test::replaced(stock, parametric, curve); };
    const std::string falling = R"({"log_h": [-3, -2, -1, 0], "density": [3.0, 2.5, 0.8, 0.1]})";
    const std::string rising = R"({"log_h": [-3, -2, -1, 0], "density": [0.1, 0.8, 2.5, 3.0]})";

    const Stock slide = parse_stock_json(with_curve(reversal, falling), "slide.json");
    CHECK(slide.kind == StockKind::reversal);
    CHECK(slide.layers[0].density_curve(-3.5) == 3.0);  // D-max at low exposure, D-min at high
    CHECK(slide.layers[0].density_curve(0.5) == 0.1);
    CHECK(parse_stock_json(stock_to_json(slide), "written").layers[0].density_curve.y == slide.layers[0].density_curve.y);

    CHECK_THAT(error_of(with_curve(reversal, rising)),
               Catch::Contains("slide.json: field 'layers[0].density_curve': the curve rises at log H -2") &&
                   Catch::Contains("a reversal film's density must not increase with exposure"));
    // The same falling curve on a negative is refused the other way round.
    CHECK_THAT(error_of(with_curve(test::test_film_json(), falling)),
               Catch::Contains("field 'layers[0].density_curve': the curve falls at log H -2"));
    CHECK_THAT(error_of(with_curve(reversal, R"({"log_h": [-3, 0], "density": [1.0, 0.95]})")),
               Catch::Contains("the curve falls 0.05 D over its exposures") && Catch::Contains("a reversal film's density must fall"));
    CHECK_THAT(error_of(reversal), Catch::Contains("field 'layers[0].density_curve.parametric': the parametric form "
                                                   "rises with exposure"));

    // softplus: a reversal film's starts from its D-max and subtracts the knots' terms.
    const std::string knots = R"("knots": [{"log_h": -2, "slope": 1.5, "width": 0.2}, {"log_h": 0, "slope": -1.5, "width": 0.2}])";
    const Stock soft = parse_stock_json(with_curve(reversal, R"({"softplus": {"d_max": 3.2, )" + knots + "}}"), "s");
    const Curve& c = soft.layers[0].density_curve;
    CHECK(c(-5) == Approx(3.2).margin(1e-6));
    CHECK(c(-1) == Approx(3.2 - 1.5).margin(1e-3));  // 1 log H past the first knot at slope 1.5
    CHECK(c(3) == Approx(3.2 - 3.0).margin(1e-3));   // held at D-min past the second
    CHECK_THAT(error_of(with_curve(reversal, R"({"softplus": {"d_min": 0.2, )" + knots + "}}")),
               Catch::Contains("field 'layers[0].density_curve.softplus.d_min': a reversal film's curve falls from "
                               "its D-max: give 'd_max'"));
    CHECK_THAT(error_of(with_curve(reversal, R"({"softplus": {"d_max": 0.5, "knots": [{"log_h": -2, "slope": -1.5, "width": 0.2}]}})")),
               Catch::Contains("the curve rises at log H"));
}

TEST_CASE("sampled curves and spectral tables are accepted unsorted", "[stock]") {
    std::string s = test::test_film_json();
    s.replace(s.find("{\"parametric\""), s.find("}}", s.find("{\"parametric\"")) + 2 - s.find("{\"parametric\""),
              R"({"log_h": [0, -2, -1, 1], "density": [1.8, 0.3, 1.0, 2.4]})");
    s.replace(s.find("{\"emulsion\": \"panchromatic\"}"), 28,
              R"({"nm": [700, 400, 550], "log10_sensitivity": [-1, 0, -0.5]})");
    Stock st = parse_stock_json(s, "sampled");
    CHECK(st.layers[0].density_curve(-1.5) == Approx(0.65));
    CHECK(st.layers[0].sensitivity[wavelength_index(400)] == Approx(1.0));
}

TEST_CASE("unknown stock ids list the built-in ones", "[stock]") {
    CHECK_THROWS_WITH(find_stock("no-such-film"), Catch::Contains("unknown stock 'no-such-film'") &&
                                                      Catch::Contains("built-in:"));
    CHECK_THROWS_WITH(find_stock("/nonexistent/stock.json"), Catch::Contains("cannot open"));
}

TEST_CASE("an unknown stock id a typo away from built-in ones suggests them, and only them", "[stock]") {
    CHECK_THROWS_WITH(find_stock("kodak-vison3-250d"), Catch::Contains("did you mean 'kodak-vision3-250d'?"));
    CHECK_THROWS_WITH(find_stock("Kodak-2383"), Catch::Contains("did you mean 'kodak-2383'?"));
    CHECK_THROWS_WITH(find_stock("kodak-t-max-200"),
                      Catch::Contains("did you mean 'kodak-t-max-100' or 'kodak-t-max-400'?"));
    CHECK_THROWS_WITH(find_stock("no-such-film"), !Catch::Contains("did you mean"));
    CHECK_THROWS_WITH(find_stock("kodak"), !Catch::Contains("did you mean"));
}

TEST_CASE("edit distance counts insertions, deletions, substitutions and swaps, case aside", "[stock]") {
    CHECK(edit_distance("develop", "develop") == 0);
    CHECK(edit_distance("devlop", "develop") == 1);
    CHECK(edit_distance("developp", "develop") == 1);
    CHECK(edit_distance("devalop", "develop") == 1);
    CHECK(edit_distance("dveelop", "develop") == 1);
    CHECK(edit_distance("DEVELOP", "develop") == 0);
    CHECK(edit_distance("", "abc") == 3);
    CHECK(edit_distance("kitten", "sitting") == 3);
    CHECK(close_names("stock", {"stocks", "demo", "plot"}) == std::vector<std::string>{"stocks"});
    CHECK(close_names("xyz", {"stocks", "demo", "plot"}).empty());
}

TEST_CASE("built-in presets parse and cite their sources", "[stock]") {
    REQUIRE(builtin_stocks().size() >= 5);
    int films = 0, papers = 0;
    for (const Stock& s : builtin_stocks()) {
        INFO(s.id);
        CHECK_FALSE(s.sources.empty());
        (s.kind == StockKind::paper ? papers : films)++;
    }
    CHECK(films >= 3);
    CHECK(papers >= 2);
}
