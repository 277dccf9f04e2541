// afterglow: one executable with subcommands (yocto's yscene, pbrt's long flags).
#include <algorithm>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "shared/input_error.h"
#include "tools/afterglow/commands.h"

namespace ag::cli {

std::vector<Subcommand>& subcommands() {
    static std::vector<Subcommand> all;
    return all;
}

}  // namespace ag::cli

namespace {

void print_usage(std::ostream& out) {
    out << "usage: afterglow COMMAND [options]\n\n"
           "Progressive global illumination in dynamic scenes (Larsen 2004).\n\ncommands:\n";
    size_t width = 10;
    for (const auto& s : ag::cli::subcommands()) width = std::max(width, s.command->name.size());
    for (const auto& s : ag::cli::subcommands()) {
        std::string name = s.command->name;
        name.resize(width, ' ');
        const std::string& summary = s.command->summary;  // first sentence only
        out << "  " << name << " " << summary.substr(0, summary.find(". ")) << "\n";
    }
    out << "\n'afterglow COMMAND --help' shows a command's options. Docs: README.md, docs/.\n";
}

}  // namespace

int main(int argc, char** argv) {
    using namespace ag::cli;
    std::stable_sort(subcommands().begin(), subcommands().end(),
                     [](const Subcommand& a, const Subcommand& b) { return a.order < b.order; });
    if (argc < 2) {
        print_usage(std::cerr);
        return 2;
    }
    const std::string name = argv[1];
    if (name == "-h" || name == "--help" || name == "help") {
        print_usage(std::cout);
        return 0;
    }
    for (const Subcommand& s : subcommands()) {
        if (s.command->name != name) continue;
        try {
            const Args args(*s.command, std::vector<std::string>(argv + 2, argv + argc));
            if (args.help()) {
                std::cout << help_text(*s.command);
                return 0;
            }
            return s.run(args);
        } catch (const CliError& e) {
            std::cerr << e.what() << "\n";
            return 2;
        } catch (const ag::InputError& e) {
            std::cerr << "afterglow: error: " << e.what() << "\n";
            return 1;
        } catch (const std::exception& e) {
            std::cerr << "afterglow " << name << ": error: " << e.what() << "\n";
            return 1;
        }
    }
    std::cerr << "afterglow: unknown command '" << name << "' (see 'afterglow --help')\n";
    return 2;
}
