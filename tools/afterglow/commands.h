// The `afterglow` subcommands: one source file each (info.cpp, export.cpp, ...).
#pragma once

#include <string>
#include <vector>

#include "tools/afterglow/cli.h"

namespace ag::cli {

struct Subcommand {
    const Command* command;
    int (*run)(const Args& args);
    int order;  // position in `afterglow --help`
};

// Every subcommand, sorted by `order`. Each subcommand's source file registers itself with a
// static `Registration`, so adding a command touches no shared file.
std::vector<Subcommand>& subcommands();

struct Registration {
    Registration(const Command& command, int (*run)(const Args&), int order) {
        subcommands().push_back({&command, run, order});
    }
};

}  // namespace ag::cli
