#include "tools/afterglow/cli.h"

#include <cmath>
#include <sstream>

namespace ag::cli {

Args::Args(const Command& command, const std::vector<std::string>& argv) : command_(command) {
    const std::string where = "afterglow " + command.name;
    for (size_t i = 0; i < argv.size(); ++i) {
        const std::string& a = argv[i];
        if (a == "-h" || a == "--help") {
            help_ = true;
            return;
        }
        if (a.size() > 1 && a[0] == '-' && !(a.size() > 1 && (std::isdigit((unsigned char)a[1]) || a[1] == '.'))) {
            std::string name = a.substr(a[1] == '-' ? 2 : 1), value;
            const bool has_inline = name.find('=') != std::string::npos;
            if (has_inline) {
                value = name.substr(name.find('=') + 1);
                name = name.substr(0, name.find('='));
            }
            const Option* opt = nullptr;
            for (const Option& o : command.options)
                if ((a[1] == '-' && o.name == name) || (a[1] != '-' && !o.alias.empty() && o.alias == name)) opt = &o;
            if (!opt)
                throw CliError(where + ": unknown option '" + a + "' (see 'afterglow " + command.name + " --help')");
            if (opt->value.empty()) {
                if (has_inline) throw CliError(where + ": option --" + opt->name + " takes no value");
                value = "1";
            } else if (!has_inline) {
                if (i + 1 >= argv.size())
                    throw CliError(where + ": option --" + opt->name + " expects a value (" + opt->value + ")");
                value = argv[++i];
            }
            values_[opt->name] = value;
        } else {
            positionals_.push_back(a);
        }
    }
    if (int(positionals_.size()) < command.min_positionals)
        throw CliError(where + ": missing argument; usage: afterglow " + command.name + " " + command.usage);
    if (int(positionals_.size()) > command.max_positionals)
        throw CliError(where + ": unexpected argument '" + positionals_[size_t(command.max_positionals)] +
                       "'; usage: afterglow " + command.name + " " + command.usage);
}

std::string Args::get(const std::string& name, const std::string& fallback) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
}

int Args::get_int(const std::string& name, int fallback, int min, int max) const {
    if (!has(name)) return fallback;
    const std::string v = get(name);
    size_t used = 0;
    long long n = 0;
    try {
        n = std::stoll(v, &used);
    } catch (...) {
        used = 0;
    }
    if (used != v.size() || v.empty() || n < min || n > max)
        throw CliError("afterglow " + command_.name + ": --" + name + " expects an integer in [" +
                       std::to_string(min) + ", " + std::to_string(max) + "], got '" + v + "'");
    return int(n);
}

double Args::get_double(const std::string& name, double fallback) const {
    if (!has(name)) return fallback;
    const std::string v = get(name);
    size_t used = 0;
    double d = 0;
    try {
        d = std::stod(v, &used);
    } catch (...) {
        used = 0;
    }
    if (used != v.size() || v.empty() || !std::isfinite(d))
        throw CliError("afterglow " + command_.name + ": --" + name + " expects a finite number, got '" + v + "'");
    return d;
}

std::string help_text(const Command& command) {
    std::ostringstream s;
    s << "usage: afterglow " << command.name << " " << command.usage << "\n\n" << command.summary << "\n\noptions:\n";
    std::vector<Option> all = command.options;
    all.push_back({"help", "h", "", "show this help"});
    for (const Option& o : all) {
        std::string flag = (o.alias.empty() ? "    " : "-" + o.alias + ", ") + "--" + o.name;
        if (!o.value.empty()) flag += " " + o.value;
        s << "  " << flag;
        for (size_t pad = flag.size(); pad < 26; ++pad) s << ' ';
        s << " " << o.help << "\n";
    }
    return s.str();
}

}  // namespace ag::cli
