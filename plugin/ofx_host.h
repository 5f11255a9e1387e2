// The host's suites, and small C++ wrappers over them that turn a failed status into an
// exception. Every action catches these at the entry point, so nothing throws into a host.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "plugin/ofx_abi.h"

namespace darkroom::ofx {

// The suites fetched at load. Property, image effect and parameter suites are required;
// the others may be null (the plugin then renders on its own thread, allocates with new,
// and has nowhere to post messages).
struct HostSuites {
    OfxHost* host = nullptr;
    const OfxPropertySuiteV1* property = nullptr;
    const OfxImageEffectSuiteV1* effect = nullptr;
    const OfxParameterSuiteV1* param = nullptr;
    const OfxMemorySuiteV1* memory = nullptr;
    const OfxMultiThreadSuiteV1* thread = nullptr;
    const OfxMessageSuiteV2* message = nullptr;
    bool persistent_messages = false;  // the message suite is version 2
};
extern HostSuites suites;

// A host call that failed: the status to return and what was being done.
struct HostError : std::runtime_error {
    OfxStatus status;
    HostError(OfxStatus s, const std::string& what) : std::runtime_error(what), status(s) {}
};

// Throws HostError unless `status` is kOfxStatOK.
void check(OfxStatus status, const char* what);

// Typed access to a property set. Getters throw HostError when the property is missing;
// the *_or forms return a fallback instead.
class Props {
public:
    explicit Props(OfxPropertySetHandle handle) : h_(handle) {}
    OfxPropertySetHandle handle() const { return h_; }

    void set(const char* name, const std::string& value, int index = 0) const;
    void set(const char* name, const char* value, int index = 0) const { set(name, std::string(value), index); }
    void set(const char* name, int value, int index = 0) const;
    void set(const char* name, double value, int index = 0) const;
    void set(const char* name, void* value, int index = 0) const;
    void set(const char* name, const std::vector<std::string>& values) const;
    void set_ints(const char* name, const std::vector<int>& values) const;
    void set_doubles(const char* name, const std::vector<double>& values) const;

    std::string get_string(const char* name, int index = 0) const;
    int get_int(const char* name, int index = 0) const;
    double get_double(const char* name, int index = 0) const;
    void* get_pointer(const char* name, int index = 0) const;
    int dimension(const char* name) const;
    std::vector<std::string> get_strings(const char* name) const;

    std::string get_string_or(const char* name, const std::string& fallback) const;
    int get_int_or(const char* name, int fallback) const;
    double get_double_or(const char* name, double fallback, int index = 0) const;

private:
    OfxPropertySetHandle h_;
};

// The property set of an effect (descriptor or instance) and of a clip.
Props effect_props(OfxImageEffectHandle effect);
Props clip_props(OfxImageClipHandle clip);

// A clip of an instance by name.
OfxImageClipHandle clip_handle(OfxImageEffectHandle effect, const char* name);

// Posts `text` on the effect: persistently where the host can (cleared by clear_message),
// else as a transient message. Does nothing when the host has no message suite.
void post_error(OfxImageEffectHandle effect, const std::string& text);
// The same for a warning, but only persistently: never as a transient message.
void post_warning(OfxImageEffectHandle effect, const std::string& text);
void clear_message(OfxImageEffectHandle effect);

}  // namespace darkroom::ofx
