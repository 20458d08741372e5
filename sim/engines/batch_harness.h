// What the batch harnesses (sim/engines/harness.cpp, sim/plasticity/harness.cpp) share: the
// refusal path (exit 2, one line), the schedule file's int64 header, the top (class Vtop) in
// its Verilated context clocked one cycle at a time, and the int64 output files.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "Vtop.h"
#include "verilated.h"

static void die(const char* msg) {
    std::fprintf(stderr, "harness: %s\n", msg);
    std::exit(2);
}

// the schedule at `path`, its first `n` int64 values read into `hdr`; the rest left to read
static FILE* open_schedule(const std::string& path, int64_t* hdr, size_t n) {
    FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) die("cannot open the schedule");
    if (std::fread(hdr, sizeof(int64_t), n, f) != n) die("short schedule header");
    return f;
}

// `n` int64 values of the schedule into `dst`, or false
static bool read_values(FILE* f, int64_t* dst, int64_t n) {
    return std::fread(dst, sizeof(int64_t), n, f) == (size_t)n;
}

// out_dir/name opened for writing
static FILE* open_output(const std::string& out_dir, const char* name, const char* mode = "wb") {
    FILE* f = std::fopen((out_dir + "/" + name).c_str(), mode);
    if (!f) die((std::string("cannot write ") + name).c_str());
    return f;
}

// `buf` appended to `f` and emptied once it holds `at` values or more (at 0: now)
static void spill(std::vector<int64_t>& buf, FILE* f, size_t at = 0) {
    if (buf.size() < at) return;
    std::fwrite(buf.data(), sizeof(int64_t), buf.size(), f);
    buf.clear();
}

// the top in its own context; cycle() is one rising clock edge
struct Clocked {
    std::unique_ptr<VerilatedContext> ctx;
    std::unique_ptr<Vtop> top;
    long long cycles = 0;
    std::chrono::steady_clock::time_point t0;
    Clocked(char** argv) : ctx(std::make_unique<VerilatedContext>()) {
        ctx->commandArgs(1, argv);
        top = std::make_unique<Vtop>(ctx.get());
    }
    void cycle() {
        top->clk = 0;
        top->eval();
        top->clk = 1;
        top->eval();
        ++cycles;
    }
    // two cycles in reset (the inputs set beforehand), then the count from zero and the clock
    void leave_reset() {
        top->rst = 1;
        cycle();
        cycle();
        top->rst = 0;
        cycles = 0;
    }
    void start_clock() { t0 = std::chrono::steady_clock::now(); }
    double wall_s() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
};
