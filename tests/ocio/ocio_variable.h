// Sets or unsets $OCIO for one test (programs the test runs inherit it) and restores it.
#pragma once

#include <cstdlib>
#include <optional>
#include <string>

struct ScopedOcioVariable {
    std::optional<std::string> saved;
    explicit ScopedOcioVariable(const std::optional<std::string>& value) {
        if (const char* old = std::getenv("OCIO")) saved = old;
        set(value);
    }
    ~ScopedOcioVariable() { set(saved); }
    static void set(const std::optional<std::string>& value) {
        if (value)
            setenv("OCIO", value->c_str(), 1);
        else
            unsetenv("OCIO");
    }
};
