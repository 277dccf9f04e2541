// A progress bar with rate and ETA on stderr (only when stderr is a terminal, or when forced).
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace ag::cli {

class Progress {
public:
    Progress(std::string label, long total, bool enabled)
        : label_(std::move(label)),
          total_(total),
          enabled_(enabled && isatty(STDERR_FILENO)),
          start_(std::chrono::steady_clock::now()) {}

    void update(long done) {
        if (!enabled_) return;
        const double elapsed =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
        const double fraction = total_ > 0 ? double(done) / double(total_) : 1.0;
        const double eta = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
        const int width = 30, filled = int(fraction * width + 0.5);
        std::fprintf(stderr, "\r%s [%.*s%*s] %3d%% %ld/%ld  %.1fs, ETA %.1fs ", label_.c_str(),
                     filled, "##############################", width - filled, "",
                     int(fraction * 100.0 + 0.5), done, total_, elapsed, eta);
        std::fflush(stderr);
    }
    void finish() {
        if (enabled_) std::fprintf(stderr, "\n");
    }

private:
    std::string label_;
    long total_;
    bool enabled_;
    std::chrono::steady_clock::time_point start_;
};

}  // namespace ag::cli
