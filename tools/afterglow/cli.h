// Command-line parsing shared by all `afterglow` subcommands, over CLI11 (kept inside cli.cpp):
// every option is declared once, with its type, range, choices and default, through the helpers
// below; values are checked while parsing. Bad flags are user errors: CliError, exit 2.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "shared/image.h"
#include "shared/settings.h"

namespace ag {
struct Scene;
}
namespace ag::gpu {
enum class GlBackend;
}

namespace ag::cli {

class CliError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

enum class OptionType { flag, text, integer, number, choice, size, settings };

struct Option {
    std::string name;   // "frames" for --frames
    std::string alias;  // "n" for -n, may be empty
    std::string value;  // placeholder shown in help ("N"); empty for a flag
    std::string help;
    OptionType type = OptionType::flag;
    double min = 0.0, max = 0.0;       // integer and number: inclusive range
    std::vector<std::string> choices;  // choice: the accepted names
    std::string default_value;         // shown in help and returned when absent; empty: none
};

// Option helpers. `names` is "long" or "long,s" (a one-letter short alias).
Option flag(const std::string& names, const std::string& help);
Option text(const std::string& names, const std::string& value, const std::string& help,
            const std::string& default_value = "");
Option integer(const std::string& names, const std::string& value, const std::string& help,
               long long min, long long max);
Option integer(const std::string& names, const std::string& value, const std::string& help,
               long long min, long long max, long long default_value);
Option number(const std::string& names, const std::string& value, const std::string& help,
              double min, double max);
Option number(const std::string& names, const std::string& value, const std::string& help,
              double min, double max, double default_value);
// A help ending in ':' gets the choices appended.
Option choice(const std::string& names, const std::string& value, const std::string& help,
              std::vector<std::string> choices, const std::string& default_value = "");
// --size WxH: positive integers up to kMaxImageSize, for every command that takes an image size.
Option size_option(const std::string& help, const std::string& default_value = "");
// --gl BACKEND restricted to `allowed` (names and help from gpu::kGlBackendNames).
Option gl_option(const std::vector<gpu::GlBackend>& allowed, gpu::GlBackend default_backend);
// --gather gl|cpu|auto (kGatherBackendNames); absent: the scene's settings.gather.backend.
Option gather_option();
// --indirect METHOD (kIndirectMethodNames); absent: the scene's settings.indirect.method.
Option indirect_option();
// --frame-ms MS: settings.schedule.frame_ms.
Option frame_ms_option();
// --set KEY=VALUE, repeatable: any scene setting (visit_settings keys, "section.key").
Option settings_option();

inline constexpr int kMaxImageSize = kMaxImageSide;  // what read_image reads back

struct Command {
    std::string name;
    std::string usage;  // e.g. "SCENE [options]"
    std::string summary;
    std::vector<Option> options;
    int min_positionals = 0, max_positionals = 0;
};

class Args {
public:
    Args(const Command& command, const std::vector<std::string>& argv);  // throws CliError
    bool help() const { return help_; }
    bool has(const std::string& name) const { return values_.count(name) > 0; }
    // The value given, else `fallback`, else the declared default.
    std::string get(const std::string& name) const;
    std::string get(const std::string& name, const std::string& fallback) const;
    int get_int(const std::string& name) const;
    int get_int(const std::string& name, int fallback) const;
    double get_double(const std::string& name) const;
    double get_double(const std::string& name, double fallback) const;
    // Index of the value in the option's choices (the given value or the default).
    int get_choice(const std::string& name) const;
    // --size WxH: overwrites width and height when given.
    void get_size(const std::string& name, int& width, int& height) const;
    gpu::GlBackend gl_backend() const;
    // --gather, --indirect, --frame-ms and every --set KEY=VALUE, in that order, onto the scene's
    // settings (rebuilding surfaces and atlas when a lightmap setting changes).
    void apply_settings(Scene& scene) const;
    const std::vector<std::string>& positionals() const { return positionals_; }

private:
    const Option& option(const std::string& name) const;

    const Command& command_;
    bool help_ = false;
    std::map<std::string, std::string> values_;
    std::vector<std::string> settings_;  // --set KEY=VALUE, in order
    std::vector<std::string> positionals_;
};

std::string help_text(const Command& command);

}  // namespace ag::cli
