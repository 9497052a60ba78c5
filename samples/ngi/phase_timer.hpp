// Wall time per phase of a command, for --timings: where a command's time goes (reading the frame, opening the
// OpenCL device, loading the model, the first run with its kernel builds, scoring, writing), printed on stderr as
// one line "timings  phase1 X ms, phase2 Y ms, ..., total Z ms" (total from the timer's creation; process start
// to main is not included). perf/small_shapes.py reads it.
#pragma once
#include <chrono>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace ngi_cli {

class PhaseTimer {
public:
    explicit PhaseTimer(bool enabled) : enabled_(enabled), start_(Clock::now()), last_(start_) {}
    // Ends the current phase under this name.
    void mark(const char* phase) {
        if (!enabled_) return;
        const auto now = Clock::now();
        phases_.emplace_back(phase, ms(last_, now));
        last_ = now;
    }
    void print() const {
        if (!enabled_) return;
        std::string line = "timings ";
        for (const auto& [name, t] : phases_) line += " " + name + " " + format(t) + " ms,";
        line += " total " + format(ms(start_, Clock::now())) + " ms";
        std::fprintf(stderr, "%s\n", line.c_str());
    }

private:
    using Clock = std::chrono::steady_clock;
    static double ms(Clock::time_point a, Clock::time_point b) {
        return std::chrono::duration<double, std::milli>(b - a).count();
    }
    static std::string format(double t) {
        char b[32];
        std::snprintf(b, sizeof b, "%.2f", t);
        return b;
    }
    bool enabled_;
    Clock::time_point start_, last_;
    std::vector<std::pair<std::string, double>> phases_;
};

}  // namespace ngi_cli
