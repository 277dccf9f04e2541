// Checked reading of JSON user input (scene files, settings blocks): every failure is an
// InputError "FILE: /json/pointer: expected ..., got ..." (docs/scene-format.md, "Errors").
#pragma once

#include <glm/glm.hpp>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace ag {

class JsonInput {
public:
    using Json = nlohmann::json;
    static constexpr double kInf = std::numeric_limits<double>::infinity();

    explicit JsonInput(std::string file) : file_(std::move(file)) {}
    const std::string& file() const { return file_; }

    [[noreturn]] void fail(const std::string& path, const std::string& message) const;

    // The JSON pointer of `key` inside the value at `path` ("~" and "/" escaped, RFC 6901).
    static std::string child(const std::string& path, std::string_view key);
    static std::string child(const std::string& path, size_t index);
    // "the string \"abc\"", "the number 2.5", "an array of 2 elements", "null", ...
    static std::string describe(const Json& value);
    static std::string format_number(double x);

    // Each checks the value at `path` and says what it expected when it fails.
    const Json& object(const Json& value, const std::string& path) const;
    const Json& array(const Json& value, const std::string& path) const;
    // Rejects keys outside `allowed`, listing them.
    void check_keys(const Json& object, const std::string& path,
                    std::initializer_list<std::string_view> allowed) const;
    // Missing required key: the message names the object's path and the key.
    const Json& require(const Json& object, const std::string& path, std::string_view key,
                        std::string_view expected) const;
    static const Json* find(const Json& object, std::string_view key);

    // A finite number in [min, max] (or (min, max) where exclusive), representable as a float.
    double number(const Json& value, const std::string& path, double min = -kInf, double max = kInf,
                  bool min_exclusive = false, bool max_exclusive = false) const;
    long long integer(const Json& value, const std::string& path, long long min,
                      long long max) const;
    bool boolean(const Json& value, const std::string& path) const;
    std::string string(const Json& value, const std::string& path, bool non_empty = true) const;
    // [x, y, z] of finite numbers, each within ±max_abs.
    glm::vec3 vec3(const Json& value, const std::string& path, double max_abs = kInf) const;
    // [r, g, b] or one number for grey, every component in [min, max].
    glm::vec3 color(const Json& value, const std::string& path, double min, double max) const;
    // One of `names` (an enum's name table); returns its index.
    template <class Names>
    int choice(const Json& value, const std::string& path, const Names& names) const {
        const std::string s = string(value, path, false);
        std::string list;
        for (size_t i = 0; i < names.size(); ++i) {
            if (s == names[i]) return int(i);
            list += (i ? ", " : "") + std::string(names[i]);
        }
        fail(path, "expected one of " + list + ", got \"" + s + "\"");
    }

private:
    std::string file_;
};

}  // namespace ag
