#include <catch2/catch.hpp>

#include "core/sensitometry.h"
#include "test_support.h"

using namespace darkroom;

static void check_report(const SensitometryReport& r) {
    for (const Measurement& m : r.measurements) {
        INFO(r.stock_id << ": " << m.name << " declared " << m.declared << " measured " << m.measured);
        CHECK(m.passes());
    }
}

TEST_CASE("sensitometry of the simulation reproduces a stock's declared values", "[sensitometry]") {
    SensitometryReport r = measure_stock(test::test_film());
    REQUIRE(r.measurements.size() == 6);
    check_report(r);
}

TEST_CASE("sensitometry measures the images, not the declared numbers", "[sensitometry]") {
    // Doubling the speed and the granularity of the stock doubles what is measured.
    std::string json = test::test_film_json(R"({"rms_granularity": 0.024, "grain_size_um": 1.5})");
    json.replace(json.find("\"iso_speed\": 200"), 16, "\"iso_speed\": 400");
    SensitometryReport base = measure_stock(test::test_film()), faster = measure_stock(parse_stock_json(json, "x"));
    CHECK(faster.measurements[0].measured / base.measurements[0].measured == Approx(2.0).epsilon(0.05));
    CHECK(faster.measurements[4].measured / base.measurements[4].measured == Approx(2.0).epsilon(0.1));
}

TEST_CASE("every built-in stock measures within tolerance of its data sheet", "[sensitometry][presets]") {
    for (const Stock& s : builtin_stocks()) check_report(measure_stock(s));
}
