// Settings: effective values, and JSON reading and writing by walking visit_settings().
#include "shared/settings.h"

#include <charconv>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <vector>

#include "shared/json_read.h"
#include "shared/settings_json.h"

namespace ag {
namespace {

using Json = nlohmann::json;

// Reads the fields one section at a time; keys nobody asked for are reported when the section
// ends, so a typo names its full path and the keys that would have been accepted.
class SettingsReader {
public:
    SettingsReader(const Json& root, const std::string& file, const std::string& path)
        : in_(file), root_(root), path_(path) {
        in_.object(root_, path_);
    }

    void section(const char* name, const char*) {
        fields_.clear();
        if (*name == '\0') {
            current_ = &root_;
            current_path_ = path_;
            return;
        }
        sections_.push_back(name);
        current_path_ = JsonInput::child(path_, name);
        current_ = JsonInput::find(root_, name);
        if (current_) in_.object(*current_, current_path_);
    }

    void end_section() {
        if (!current_) return;
        const bool top = current_ == &root_;
        for (const auto& item : current_->items()) {
            bool known = false;
            for (const std::string& f : fields_) known = known || f == item.key();
            if (top)
                for (const std::string& s : sections_) known = known || s == item.key();
            if (known) continue;
            std::string list;
            for (const std::string& f : fields_) list += (list.empty() ? "" : ", ") + f;
            if (top)
                for (const std::string& s : sections_) list += (list.empty() ? "" : ", ") + s;
            in_.fail(JsonInput::child(current_path_, item.key()),
                     "unknown key; expected one of " + list);
        }
        current_ = nullptr;
    }

    template <class T>
    void field(const Field<T>& f) {
        const Json* value = lookup(f.name);
        if (!value) return;
        const std::string path = JsonInput::child(current_path_, f.name);
        if constexpr (std::is_same_v<T, bool>) {
            f.value = in_.boolean(*value, path);
        } else if constexpr (std::is_integral_v<T>) {
            f.value = T(in_.integer(*value, path, (long long)f.min, (long long)f.max));
        } else {
            f.value = T(in_.number(*value, path, f.min, f.max));
        }
    }

    template <class E, size_t N>
    void field(const EnumField<E, N>& f) {
        const Json* value = lookup(f.name);
        if (!value) return;
        f.value = E(in_.choice(*value, JsonInput::child(current_path_, f.name), f.names));
    }

private:
    const Json* lookup(const char* name) {
        fields_.push_back(name);
        return current_ ? JsonInput::find(*current_, name) : nullptr;
    }

    JsonInput in_;
    const Json& root_;
    std::string path_;
    const Json* current_ = nullptr;
    std::string current_path_;
    std::vector<std::string> fields_;
    std::vector<std::string> sections_;
};

class SettingsWriter {
public:
    Json out = Json::object();

    void section(const char* name, const char*) { section_ = name; }
    void end_section() {}

    template <class T>
    void field(const Field<T>& f) {
        if constexpr (std::is_same_v<T, float>) {
            // Through the float's shortest decimal form, so 1e-4f prints as 0.0001.
            char buffer[32];
            const auto end = std::to_chars(buffer, buffer + sizeof buffer, f.value).ptr;
            target()[f.name] = std::strtod(std::string(buffer, end).c_str(), nullptr);
        } else {
            target()[f.name] = f.value;
        }
    }
    template <class E, size_t N>
    void field(const EnumField<E, N>& f) {
        target()[f.name] = f.names[size_t(f.value)];
    }

private:
    Json& target() { return section_.empty() ? out : out[section_]; }
    std::string section_;
};

}  // namespace

float effective_texel_size(const Settings& settings, float longest_scene_extent) {
    if (settings.lightmap.texel_size > 0.0f) return settings.lightmap.texel_size;
    // Larsen's Cornell walls carry 5×5 texels (ch. 14); at that size the IIM, read between texel
    // centres, misses the light's rise towards creases and contacts and the Cornell indirect term
    // reads 4% dark against per-pixel gathering (docs/fidelity.md). 10×10 brings it within 1%.
    return longest_scene_extent > 0.0f ? longest_scene_extent / 10.0f : 1.0f;
}

void read_settings(const nlohmann::json& json, Settings& settings, const std::string& file,
                   const std::string& path) {
    SettingsReader reader(json, file, path);
    visit_settings(settings, reader);
}

nlohmann::json settings_to_json_value(const Settings& settings) {
    Settings copy = settings;  // visit_settings takes a mutable reference; the writer only reads
    SettingsWriter writer;
    visit_settings(copy, writer);
    return writer.out;
}

std::string settings_to_json(const Settings& settings) {
    return settings_to_json_value(settings).dump(4);
}

}  // namespace ag
