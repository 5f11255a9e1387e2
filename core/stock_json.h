// Reading stock files: a JSON field reader whose every error names the file, the field
// path and the problem. Shared by the darkroom-stock parser and the spektrafilm importer.
#pragma once

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/json_message.h"
#include "core/stock.h"

namespace darkroom::stock_json {

using nlohmann::json;

// The largest magnitude of a plain number in a stock file (table values, log H).
inline constexpr double kHuge = 1e30;
// Every density a stock's curves may reach, however they are given (tables, softplus knots,
// the parametric form, an imported profile), so that a stock written by stock_to_json reads back.
inline constexpr double kMaxDensity = 10.0;
// The speeds a stock may have (ISO arithmetic), however it is given or derived.
inline constexpr double kMinIsoSpeed = 1e-6;
inline constexpr double kMaxIsoSpeed = 1e9;
// log10 sensitivities are read within +-30, so that 10^x is a finite, non-zero double.
inline constexpr double kMaxLog10Sensitivity = 30.0;
// The least a density curve rises over its exposures: a flatter film records no picture.
inline constexpr double kMinDensityRise = 0.1;
// Physical ranges: a grain clump is a few um (the coarsest films' under 3); a halo, light
// reflected by the base's back (some 0.13 mm thick), spreads a few hundred um.
inline constexpr double kMaxGrainSizeUm = 50.0;
inline constexpr double kMaxHalationRadiusUm = 5000.0;
// DIR couplers: log10 H of inhibition per unit net density, and the inhibitor's spread.
inline constexpr double kMaxDirCoupling = 2.0;
inline constexpr double kMaxDirDiffusionUm = 500.0;

// Reads fields of a JSON document, naming the file and the field path in every error.
class FieldReader {
public:
    FieldReader(std::string origin, std::string path) : origin_(std::move(origin)), path_(std::move(path)) {}

    [[noreturn]] void fail(const std::string& problem) const {
        throw StockError(origin_ + ": field '" + path_ + "': " + problem);
    }
    FieldReader at(const std::string& key) const { return {origin_, path_.empty() ? key : path_ + "." + key}; }
    FieldReader at(size_t i) const { return {origin_, path_ + "[" + std::to_string(i) + "]"}; }

    const json& field(const json& obj, const std::string& key) const {
        if (!obj.is_object()) fail("expected an object");
        auto it = obj.find(key);
        if (it == obj.end()) at(key).fail("missing");
        return *it;
    }
    double number(const json& v, double min, double max) const {
        if (!v.is_number()) fail("expected a number, got " + json_for_message(v));
        double d = v.get<double>();
        if (!std::isfinite(d) || d < min || d > max) {
            std::ostringstream s;
            s << "value " << d << " is outside [" << min << ", " << max << "]";
            fail(s.str());
        }
        return d;
    }
    std::string text(const json& v) const {
        if (!v.is_string()) fail("expected a string, got " + json_for_message(v));
        return v.get<std::string>();
    }
    std::vector<double> numbers(const json& v, double min, double max) const {
        if (!v.is_array() || v.empty()) fail("expected a non-empty array of numbers");
        std::vector<double> out;
        for (size_t i = 0; i < v.size(); ++i) out.push_back(at(i).number(v[i], min, max));
        return out;
    }
    const std::string& path() const { return path_; }

private:
    std::string origin_, path_;
};

// The document in `text`; throws StockError naming `origin` if it is not valid JSON (a
// syntax error, or a number too large for a double: nlohmann-json's out_of_range).
inline json parse_document(const std::string& text, const std::string& origin) {
    try {
        return json::parse(text);
    } catch (const json::exception& e) {
        throw StockError(origin + ": not valid JSON: " + e.what());
    }
}

// A parsed spektrafilm profile as a stock (core/stock_import.cpp).
Stock stock_from_spektrafilm(const json& doc, const std::string& origin);

}  // namespace darkroom::stock_json
