// How the file parsers (stocks, grain profiles, look files) show a JSON value in an error
// message: a scalar as written, an array or object only by its kind and size. nlohmann-json
// parses any depth without recursion, but dump() recurses once per level, so dumping a value
// nested a few hundred thousand levels deep would overflow the stack (found by fuzzing).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace darkroom {

inline std::string json_for_message(const nlohmann::json& value) {
    if (value.is_array()) return "an array of size " + std::to_string(value.size());
    if (value.is_object()) return "an object of size " + std::to_string(value.size());
    return value.dump();
}

}  // namespace darkroom
