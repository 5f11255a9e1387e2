#include "plugin/ofx_host.h"

namespace darkroom::ofx {

HostSuites suites;

void check(OfxStatus status, const char* what) {
    if (status != kOfxStatOK) throw HostError(status, std::string(what) + " failed (OFX status " + std::to_string(status) + ")");
}

namespace {
std::string prop_what(const char* verb, const char* name) { return std::string(verb) + " property " + name; }
}  // namespace

void Props::set(const char* name, const std::string& value, int index) const {
    check(suites.property->propSetString(h_, name, index, value.c_str()), prop_what("setting", name).c_str());
}
void Props::set(const char* name, int value, int index) const {
    check(suites.property->propSetInt(h_, name, index, value), prop_what("setting", name).c_str());
}
void Props::set(const char* name, double value, int index) const {
    check(suites.property->propSetDouble(h_, name, index, value), prop_what("setting", name).c_str());
}
void Props::set(const char* name, void* value, int index) const {
    check(suites.property->propSetPointer(h_, name, index, value), prop_what("setting", name).c_str());
}
void Props::set(const char* name, const std::vector<std::string>& values) const {
    for (size_t i = 0; i < values.size(); ++i) set(name, values[i], (int)i);
}
void Props::set_ints(const char* name, const std::vector<int>& values) const {
    check(suites.property->propSetIntN(h_, name, (int)values.size(), values.data()), prop_what("setting", name).c_str());
}
void Props::set_doubles(const char* name, const std::vector<double>& values) const {
    check(suites.property->propSetDoubleN(h_, name, (int)values.size(), values.data()),
          prop_what("setting", name).c_str());
}

std::string Props::get_string(const char* name, int index) const {
    char* value = nullptr;
    check(suites.property->propGetString(h_, name, index, &value), prop_what("reading", name).c_str());
    return value ? value : "";
}
int Props::get_int(const char* name, int index) const {
    int value = 0;
    check(suites.property->propGetInt(h_, name, index, &value), prop_what("reading", name).c_str());
    return value;
}
double Props::get_double(const char* name, int index) const {
    double value = 0;
    check(suites.property->propGetDouble(h_, name, index, &value), prop_what("reading", name).c_str());
    return value;
}
void* Props::get_pointer(const char* name, int index) const {
    void* value = nullptr;
    check(suites.property->propGetPointer(h_, name, index, &value), prop_what("reading", name).c_str());
    return value;
}
int Props::dimension(const char* name) const {
    int count = 0;
    check(suites.property->propGetDimension(h_, name, &count), prop_what("reading", name).c_str());
    return count;
}
std::vector<std::string> Props::get_strings(const char* name) const {
    std::vector<std::string> values;
    for (int i = 0, n = dimension(name); i < n; ++i) values.push_back(get_string(name, i));
    return values;
}

std::string Props::get_string_or(const char* name, const std::string& fallback) const {
    char* value = nullptr;
    return suites.property->propGetString(h_, name, 0, &value) == kOfxStatOK && value ? value : fallback;
}
int Props::get_int_or(const char* name, int fallback) const {
    int value = 0;
    return suites.property->propGetInt(h_, name, 0, &value) == kOfxStatOK ? value : fallback;
}
double Props::get_double_or(const char* name, double fallback, int index) const {
    double value = 0;
    return suites.property->propGetDouble(h_, name, index, &value) == kOfxStatOK ? value : fallback;
}

Props effect_props(OfxImageEffectHandle effect) {
    OfxPropertySetHandle h = nullptr;
    check(suites.effect->getPropertySet(effect, &h), "getting the effect's properties");
    return Props(h);
}

Props clip_props(OfxImageClipHandle clip) {
    OfxPropertySetHandle h = nullptr;
    check(suites.effect->clipGetPropertySet(clip, &h), "getting a clip's properties");
    return Props(h);
}

OfxImageClipHandle clip_handle(OfxImageEffectHandle effect, const char* name) {
    OfxImageClipHandle clip = nullptr;
    check(suites.effect->clipGetHandle(effect, name, &clip, nullptr), (std::string("getting clip ") + name).c_str());
    return clip;
}

namespace {

void post_message(OfxImageEffectHandle effect, const char* type, const std::string& text) {
    if (!suites.message) return;
    // The text goes through "%s" so that a '%' in a file name is never read as a format.
    if (suites.persistent_messages && effect)
        suites.message->setPersistentMessage(effect, type, "", "%s", text.c_str());
    else
        suites.message->message(effect, type, "", "%s", text.c_str());
}

}  // namespace

void post_error(OfxImageEffectHandle effect, const std::string& text) { post_message(effect, kOfxMessageError, text); }

void post_warning(OfxImageEffectHandle effect, const std::string& text) {
    // Only on the node: a transient message can be a dialog, and a render posts it every frame.
    if (suites.persistent_messages) post_message(effect, kOfxMessageWarning, text);
}

void clear_message(OfxImageEffectHandle effect) {
    if (suites.message && suites.persistent_messages && effect) suites.message->clearPersistentMessage(effect);
}

}  // namespace darkroom::ofx
