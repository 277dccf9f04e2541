// Checked reading of JSON user input.
#include "shared/json_read.h"

#include <cfloat>
#include <cmath>
#include <cstdio>

#include "shared/input_error.h"

namespace ag {
namespace {

std::string range_text(double min, double max, bool min_exclusive, bool max_exclusive) {
    const bool has_min = std::isfinite(min), has_max = std::isfinite(max);
    if (has_min && has_max)
        return std::string(min_exclusive ? "in (" : "in [") + JsonInput::format_number(min) + ", " +
               JsonInput::format_number(max) + (max_exclusive ? ")" : "]");
    if (has_min) return std::string(min_exclusive ? "> " : ">= ") + JsonInput::format_number(min);
    if (has_max) return std::string(max_exclusive ? "< " : "<= ") + JsonInput::format_number(max);
    return "";
}

}  // namespace

void JsonInput::fail(const std::string& path, const std::string& message) const {
    throw_input_error(file_, path.empty() ? "/" : path, message);
}

std::string JsonInput::child(const std::string& path, std::string_view key) {
    std::string out = path + "/";
    for (char c : key) {
        if (c == '~')
            out += "~0";
        else if (c == '/')
            out += "~1";
        else
            out += c;
    }
    return out;
}

std::string JsonInput::child(const std::string& path, size_t index) {
    return path + "/" + std::to_string(index);
}

std::string JsonInput::format_number(double x) {
    if (std::isfinite(x) && x == std::floor(x) && std::fabs(x) < 1e15) {
        return std::to_string((long long)x);
    }
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.7g", x);
    return buffer;
}

std::string JsonInput::describe(const Json& value) {
    switch (value.type()) {
        case Json::value_t::null:
            return "null";
        case Json::value_t::boolean:
            return value.get<bool>() ? "true" : "false";
        case Json::value_t::string: {
            std::string s = value.get<std::string>();
            if (s.size() > 40) s = s.substr(0, 37) + "...";
            return "the string \"" + s + "\"";
        }
        case Json::value_t::number_integer:
        case Json::value_t::number_unsigned:
        case Json::value_t::number_float:
            return format_number(value.get<double>());
        case Json::value_t::array:
            return value.empty() ? "an empty array"
                                 : "an array of " + std::to_string(value.size()) +
                                       (value.size() == 1 ? " element" : " elements");
        case Json::value_t::object:
            return "an object";
        default:
            return "an unsupported value";
    }
}

const JsonInput::Json& JsonInput::object(const Json& value, const std::string& path) const {
    if (!value.is_object()) fail(path, "expected an object {...}, got " + describe(value));
    return value;
}

const JsonInput::Json& JsonInput::array(const Json& value, const std::string& path) const {
    if (!value.is_array()) fail(path, "expected an array [...], got " + describe(value));
    return value;
}

void JsonInput::check_keys(const Json& obj, const std::string& path,
                           std::initializer_list<std::string_view> allowed) const {
    for (const auto& item : obj.items()) {
        bool known = false;
        for (std::string_view a : allowed) known = known || item.key() == a;
        if (known) continue;
        std::string list;
        for (std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        fail(child(path, item.key()), "unknown key; expected one of " + list);
    }
}

const JsonInput::Json* JsonInput::find(const Json& obj, std::string_view key) {
    const auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
}

const JsonInput::Json& JsonInput::require(const Json& obj, const std::string& path,
                                          std::string_view key, std::string_view expected) const {
    const Json* value = find(obj, key);
    if (!value)
        fail(path, "missing key \"" + std::string(key) + "\"; expected " + std::string(expected));
    return *value;
}

double JsonInput::number(const Json& value, const std::string& path, double min, double max,
                         bool min_exclusive, bool max_exclusive) const {
    const std::string range = range_text(min, max, min_exclusive, max_exclusive);
    const std::string expected = "expected a number" + (range.empty() ? "" : " " + range);
    if (!value.is_number()) fail(path, expected + ", got " + describe(value));
    const double x = value.get<double>();
    // Everything downstream is float: a value that only a double can hold is as unusable as inf.
    if (!std::isfinite(x) || std::fabs(x) > double(FLT_MAX))
        fail(path, "expected a finite number, got " + describe(value));
    if (x < min || x > max || (min_exclusive && x == min) || (max_exclusive && x == max))
        fail(path, expected + ", got " + describe(value));
    return x;
}

long long JsonInput::integer(const Json& value, const std::string& path, long long min,
                             long long max) const {
    const std::string expected =
        "expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
    if (!value.is_number()) fail(path, expected + ", got " + describe(value));
    if (value.is_number_unsigned()) {
        const unsigned long long u = value.get<unsigned long long>();
        if (u > (unsigned long long)max || (min > 0 && u < (unsigned long long)min))
            fail(path, expected + ", got " + describe(value));
        return (long long)u;
    }
    if (value.is_number_integer()) {
        const long long i = value.get<long long>();
        if (i < min || i > max) fail(path, expected + ", got " + describe(value));
        return i;
    }
    const double x = value.get<double>();  // 2.0 is as good as 2; 2.5 is not
    if (!std::isfinite(x) || x != std::floor(x) || x < double(min) || x > double(max))
        fail(path, expected + ", got " + describe(value));
    return (long long)x;
}

bool JsonInput::boolean(const Json& value, const std::string& path) const {
    if (!value.is_boolean()) fail(path, "expected true or false, got " + describe(value));
    return value.get<bool>();
}

std::string JsonInput::string(const Json& value, const std::string& path, bool non_empty) const {
    if (!value.is_string()) fail(path, "expected a string, got " + describe(value));
    std::string s = value.get<std::string>();
    if (non_empty && s.empty()) fail(path, "expected a non-empty string, got \"\"");
    return s;
}

glm::vec3 JsonInput::vec3(const Json& value, const std::string& path, double max_abs) const {
    if (!value.is_array() || value.size() != 3)
        fail(path, "expected [x, y, z], got " + describe(value));
    glm::vec3 v;
    for (int k = 0; k < 3; ++k)
        v[k] = float(number(value[size_t(k)], child(path, size_t(k)), -max_abs, max_abs));
    return v;
}

glm::vec3 JsonInput::color(const Json& value, const std::string& path, double min,
                           double max) const {
    if (value.is_number()) return glm::vec3(float(number(value, path, min, max)));
    if (!value.is_array() || value.size() != 3)
        fail(path, "expected [r, g, b] or one number, got " + describe(value));
    glm::vec3 c;
    for (int k = 0; k < 3; ++k)
        c[k] = float(number(value[size_t(k)], child(path, size_t(k)), min, max));
    return c;
}

}  // namespace ag
