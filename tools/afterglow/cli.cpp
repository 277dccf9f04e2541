#include "tools/afterglow/cli.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cassert>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "gpu/gl_context.h"
#include "shared/input_error.h"
#include "shared/scene.h"
#include "shared/scene_file.h"
#include "shared/settings_json.h"

namespace ag::cli {

namespace {

Option make_option(const std::string& names, const std::string& value, const std::string& help,
                   OptionType type) {
    Option o;
    const size_t comma = names.find(',');
    o.name = names.substr(0, comma);
    if (comma != std::string::npos) o.alias = names.substr(comma + 1);
    o.value = value;
    o.help = help;
    o.type = type;
    return o;
}

std::string format_number(double d) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", d);
    return buf;
}

// WxH (or WXH) with 1 <= W, H <= kMaxImageSize; false for anything else.
bool parse_size(const std::string& text, int& width, int& height) {
    // Digits only, checked against the limit while reading: sscanf("%d") wraps on overflow
    // (4294967328x32 read as 32x32).
    size_t i = 0;
    auto read_dimension = [&](int& value) {
        long long v = 0;
        const size_t start = i;
        for (; i < text.size() && std::isdigit(static_cast<unsigned char>(text[i])); ++i) {
            v = v * 10 + (text[i] - '0');
            if (v > kMaxImageSize) return false;
        }
        value = int(v);
        return i > start && v >= 1;
    };
    int w = 0, h = 0;
    if (!read_dimension(w) || i >= text.size() || (text[i] != 'x' && text[i] != 'X')) return false;
    ++i;
    if (!read_dimension(h) || i != text.size()) return false;
    width = w;
    height = h;
    return true;
}

// "section.key=value" (or "key=value" for the top-level seed and threads) onto `settings`,
// through read_settings() so that keys, ranges and enum names are the scene file's.
void apply_setting(const std::string& assignment, Settings& settings) {
    const size_t eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0)
        throw InputError("expects KEY=VALUE (e.g. gather.backend=cpu), got '" + assignment + "'");
    const std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
    // Numbers and booleans as JSON, anything else (enum names) as a string.
    nlohmann::json value = nlohmann::json::parse(text, nullptr, false);
    if (value.is_discarded() || value.is_structured()) value = text;
    nlohmann::json json = nlohmann::json::object();
    const size_t dot = key.find('.');
    if (dot == std::string::npos)
        json[key] = value;
    else
        json[key.substr(0, dot)][key.substr(dot + 1)] = value;
    read_settings(json, settings, "'" + assignment + "'", "");
}

CLI::Validator size_validator() {
    return CLI::Validator(
        [](std::string& text) {
            int w = 0, h = 0;
            if (parse_size(text, w, h)) return std::string();
            return "expects WxH with positive integers up to " + std::to_string(kMaxImageSize) +
                   ", got '" + text + "'";
        },
        "WxH", "size");
}

CLI::Validator finite_validator() {
    return CLI::Validator(
        [](std::string& text) {
            double d = 0.0;
            if (CLI::detail::lexical_cast(text, d) && std::isfinite(d)) return std::string();
            return "expects a finite number, got '" + text + "'";
        },
        "NUMBER", "finite");
}

CLI::Validator settings_validator() {
    return CLI::Validator(
        [](std::string& text) {
            Settings scratch;
            try {
                apply_setting(text, scratch);
            } catch (const InputError& e) {
                return std::string(e.what());
            }
            return std::string();
        },
        "KEY=VALUE", "setting");
}

}  // namespace

Option flag(const std::string& names, const std::string& help) {
    return make_option(names, "", help, OptionType::flag);
}

Option text(const std::string& names, const std::string& value, const std::string& help,
            const std::string& default_value) {
    Option o = make_option(names, value, help, OptionType::text);
    o.default_value = default_value;
    return o;
}

Option integer(const std::string& names, const std::string& value, const std::string& help,
               long long min, long long max) {
    Option o = make_option(names, value, help, OptionType::integer);
    o.min = double(min);
    o.max = double(max);
    return o;
}

Option integer(const std::string& names, const std::string& value, const std::string& help,
               long long min, long long max, long long default_value) {
    Option o = integer(names, value, help, min, max);
    o.default_value = std::to_string(default_value);
    return o;
}

Option number(const std::string& names, const std::string& value, const std::string& help,
              double min, double max) {
    Option o = make_option(names, value, help, OptionType::number);
    o.min = min;
    o.max = max;
    return o;
}

Option number(const std::string& names, const std::string& value, const std::string& help,
              double min, double max, double default_value) {
    Option o = number(names, value, help, min, max);
    o.default_value = format_number(default_value);
    return o;
}

Option choice(const std::string& names, const std::string& value, const std::string& help,
              std::vector<std::string> choices, const std::string& default_value) {
    Option o = make_option(names, value, help, OptionType::choice);
    if (!o.help.empty() && o.help.back() == ':')
        for (size_t i = 0; i < choices.size(); ++i) o.help += (i ? ", " : " ") + choices[i];
    o.choices = std::move(choices);
    o.default_value = default_value;
    return o;
}

Option size_option(const std::string& help, const std::string& default_value) {
    Option o = make_option("size", "WxH", help, OptionType::size);
    o.default_value = default_value;
    return o;
}

Option gl_option(const std::vector<gpu::GlBackend>& allowed, gpu::GlBackend default_backend) {
    std::vector<std::string> names;
    std::string help;
    for (gpu::GlBackend b : allowed) {
        const std::string name = gpu::kGlBackendNames[size_t(b)];
        names.push_back(name);
        help += (help.empty() ? "" : ", ") + name;
        if (b == gpu::GlBackend::automatic) help += " (EGL on a GPU, else OSMesa)";
        if (b == gpu::GlBackend::window) help += " (a GLFW window)";
    }
    return choice("gl", "BACKEND", "GL context: " + help, names,
                  gpu::kGlBackendNames[size_t(default_backend)]);
}

Option gather_option() {
    return choice("gather", "BACKEND",
                  "gl | cpu | auto (measure both, keep the faster): the IIM gather backend "
                  "(default: the scene's settings.gather.backend)",
                  {kGatherBackendNames.begin(), kGatherBackendNames.end()});
}

Option indirect_option() {
    return choice("indirect", "METHOD",
                  "where the indirect term comes from (default: the scene's "
                  "settings.indirect.method):",
                  {kIndirectMethodNames.begin(), kIndirectMethodNames.end()});
}

Option frame_ms_option() {
    return number("frame-ms", "MS",
                  "frame-time target: work is scheduled by measured cost to fill it (0: the fixed "
                  "per-frame counts; default: the scene's settings.schedule.frame_ms)",
                  0, 1e6);
}

Option settings_option() {
    return make_option("set", "KEY=VALUE",
                       "override a scene setting, e.g. gather.texels_per_frame=40 or seed=7 (keys "
                       "as printed by 'afterglow info SCENE --settings'); repeatable",
                       OptionType::settings);
}

Args::Args(const Command& command, const std::vector<std::string>& argv) : command_(command) {
    const std::string where = "afterglow " + command.name;
    CLI::App app(command.summary, where);
    app.set_help_flag("-h,--help");
    app.allow_extras();  // unknown options are reported below, naming the first
    std::map<std::string, std::string> text;
    std::map<std::string, bool> flags;
    app.add_option("positionals", positionals_);
    for (const Option& o : command.options) {
        const std::string names = "--" + o.name + (o.alias.empty() ? "" : ",-" + o.alias);
        if (o.type == OptionType::flag) {
            app.add_flag(names, flags[o.name])->disable_flag_override();
            continue;
        }
        if (o.type == OptionType::settings) {
            // One KEY=VALUE per --set (the next argument may be the scene), all of them kept.
            app.add_option(names, settings_)
                ->expected(1)
                ->allow_extra_args(false)
                ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
                ->check(settings_validator());
            continue;
        }
        CLI::Option* opt = app.add_option(names, text[o.name]);
        opt->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
        switch (o.type) {
            case OptionType::integer:
                opt->check(
                    CLI::Range(static_cast<long long>(o.min), static_cast<long long>(o.max)));
                break;
            case OptionType::number:
                opt->check(finite_validator())->check(CLI::Range(o.min, o.max));
                break;
            case OptionType::choice:
                opt->check(CLI::IsMember(o.choices));
                break;
            case OptionType::size:
                opt->check(size_validator());
                break;
            default:
                break;
        }
    }

    // CLI11 takes the arguments reversed; "-n=2" (which CLI11 reads as "-n" "=2") as "-n" "2".
    std::vector<std::string> reversed;
    for (auto it = argv.rbegin(); it != argv.rend(); ++it) {
        const std::string& a = *it;
        const bool short_inline =
            a.size() > 2 && a[0] == '-' && std::isalpha((unsigned char)a[1]) && a[2] == '=';
        if (short_inline) reversed.push_back(a.substr(3));
        reversed.push_back(short_inline ? a.substr(0, 2) : a);
    }
    try {
        app.parse(std::move(reversed));
    } catch (const CLI::CallForHelp&) {
        help_ = true;
        return;
    } catch (const CLI::ArgumentMismatch& e) {
        // A value missing after an option, or one given to a flag: say which, in our words.
        const std::string what = e.what();
        for (const Option& o : command.options) {
            const std::string flag_name = "--" + o.name;
            if (what.rfind(flag_name + ":", 0) != 0 && what.rfind(o.name + " was given", 0) != 0)
                continue;
            throw CliError(
                where + ": option " + flag_name +
                (o.value.empty() ? " takes no value" : " expects a value (" + o.value + ")"));
        }
        throw CliError(where + ": " + what + " (see '" + where + " --help')");
    } catch (const CLI::ParseError& e) {
        throw CliError(where + ": " + e.what() + " (see '" + where + " --help')");
    }
    for (const std::string& extra : app.remaining())
        throw CliError(where + ": unknown option '" + extra + "' (see '" + where + " --help')");

    for (const Option& o : command.options) {
        if (o.type == OptionType::flag && flags[o.name]) values_[o.name] = "1";
        if (o.type != OptionType::flag && o.type != OptionType::settings &&
            app.get_option("--" + o.name)->count() > 0)
            values_[o.name] = text[o.name];
    }
    if (!settings_.empty()) values_["set"] = settings_.back();

    if (int(positionals_.size()) < command.min_positionals)
        throw CliError(where + ": missing argument; usage: " + where + " " + command.usage);
    if (int(positionals_.size()) > command.max_positionals)
        throw CliError(where + ": unexpected argument '" +
                       positionals_[size_t(command.max_positionals)] + "'; usage: " + where + " " +
                       command.usage);
}

const Option& Args::option(const std::string& name) const {
    for (const Option& o : command_.options)
        if (o.name == name) return o;
    assert(false && "option not declared by this command");
    throw std::logic_error("afterglow " + command_.name + ": no option --" + name);
}

std::string Args::get(const std::string& name) const {
    return get(name, option(name).default_value);
}

std::string Args::get(const std::string& name, const std::string& fallback) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
}

int Args::get_int(const std::string& name) const {
    const std::string v = get(name);
    if (v.empty())
        throw std::logic_error("afterglow " + command_.name + ": --" + name + " has no default");
    return std::stoi(v);  // checked against the declared range while parsing
}

int Args::get_int(const std::string& name, int fallback) const {
    return has(name) ? get_int(name) : fallback;
}

double Args::get_double(const std::string& name) const {
    const std::string v = get(name);
    if (v.empty())
        throw std::logic_error("afterglow " + command_.name + ": --" + name + " has no default");
    return std::stod(v);
}

double Args::get_double(const std::string& name, double fallback) const {
    return has(name) ? get_double(name) : fallback;
}

int Args::get_choice(const std::string& name) const {
    const Option& o = option(name);
    const std::string v = get(name);
    const auto it = std::find(o.choices.begin(), o.choices.end(), v);
    if (it == o.choices.end())
        throw std::logic_error("afterglow " + command_.name + ": --" + name + " has no value");
    return int(it - o.choices.begin());
}

void Args::get_size(const std::string& name, int& width, int& height) const {
    const std::string v = get(name);
    if (!v.empty()) parse_size(v, width, height);  // checked while parsing
}

gpu::GlBackend Args::gl_backend() const { return gpu::parse_gl_backend(get("gl")); }

void Args::apply_settings(Scene& scene) const {
    if (has("gather")) scene.settings.gather.backend = GatherBackend(get_choice("gather"));
    if (has("frame-ms")) scene.settings.schedule.frame_ms = float(get_double("frame-ms"));
    if (has("indirect"))
        scene.settings.indirect.method = IndirectMethodKind(get_choice("indirect"));
    const LightmapSettings before = scene.settings.lightmap;
    for (const std::string& s : settings_) apply_setting(s, scene.settings);  // checked on parse
    if (settings_.empty()) return;
    // Each value was checked alone while parsing; what depends on the scene (its lights, its
    // size) is checked again, as loading checked it, before anything is allocated.
    try {
        settings_changed(scene, before);
    } catch (const InputError& e) {
        throw CliError("afterglow " + command_.name + ": --set: " + e.what());
    }
}

std::string help_text(const Command& command) {
    std::ostringstream s;
    s << "usage: afterglow " << command.name << " " << command.usage << "\n\n"
      << command.summary << "\n\noptions:\n";
    std::vector<Option> all = command.options;
    all.push_back(flag("help,h", "show this help"));
    for (const Option& o : all) {
        std::string names = (o.alias.empty() ? "    " : "-" + o.alias + ", ") + "--" + o.name;
        if (!o.value.empty()) names += " " + o.value;
        s << "  " << names;
        for (size_t pad = names.size(); pad < 26; ++pad) s << ' ';
        s << " " << o.help;
        if (!o.default_value.empty()) s << " (default " << o.default_value << ")";
        s << "\n";
    }
    return s.str();
}

}  // namespace ag::cli
