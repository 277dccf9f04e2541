// Command-line parsing shared by all `afterglow` subcommands: long flags (--name value, --name=value,
// boolean --name), short aliases, positionals. Bad flags are user errors: CliError, exit 2.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace ag::cli {

class CliError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct Option {
    std::string name;       // "frames" for --frames
    std::string alias;      // "o" for -o, may be empty
    std::string value;      // placeholder shown in help ("N"); empty = boolean flag
    std::string help;
};

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
    std::string get(const std::string& name, const std::string& fallback = "") const;
    int get_int(const std::string& name, int fallback, int min, int max) const;
    double get_double(const std::string& name, double fallback) const;
    const std::vector<std::string>& positionals() const { return positionals_; }

private:
    const Command& command_;
    bool help_ = false;
    std::map<std::string, std::string> values_;
    std::vector<std::string> positionals_;
};

std::string help_text(const Command& command);

}  // namespace ag::cli
