// The `afterglow` subcommands: one source file each (info.cpp, export.cpp, ...).
#pragma once

#include <string>
#include <vector>

#include "tools/afterglow/cli.h"

namespace ag::cli {

struct Subcommand {
    const Command* command;
    int (*run)(const Args& args);
};

// Every subcommand, in the order `afterglow --help` lists them.
const std::vector<Subcommand>& subcommands();

extern const Command kInfoCommand;
int run_info(const Args& args);
extern const Command kExportCommand;
int run_export(const Args& args);
extern const Command kPhotonsCommand;
int run_photons(const Args& args);
extern const Command kBenchCommand;
int run_bench(const Args& args);

}  // namespace ag::cli
