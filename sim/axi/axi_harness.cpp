// A block behind the AXI face (AxiTop) compiled by Verilator, driven by the host's bus
// transactions (the `axi` engine): an AXI4-Stream source on s_axis, an AXI4-Stream sink on
// m_axis (always ready) and an AXI4-Lite master on s_axil, one transaction at a time.
//
// Each cycle the inputs are set, the model is evaluated with the clock low (its combinational
// outputs settle: the handshakes of the coming edge are read then), and the clock rises.
// Spike beats are recorded whatever the request (the sink never stalls).
//
// Protocol on stdin/stdout (little-endian binary), one request, one answer:
//   'W' u32 n, n x (u32 addr, i32 value)   a write burst (TLAST on its last beat)
//        -> u64 cycle                         once every beat is taken
//   'L' u32 addr, u32 data                  an AXI4-Lite write of the whole word
//        -> u8 bresp, u64 cycle
//   'R' u32 addr                            an AXI4-Lite read
//        -> u32 data, u8 rresp, u64 cycle
//   'S' u64 sweeps, u64 max_cycles          run until `sweeps` beats with TLAST have come
//                                           since reset, or max_cycles more cycles
//        -> u32 m, m x (u64 tdata, u8 tlast | tuser << 1), u64 cycle, u8 why (0 done,
//           2 max_cycles): every beat since the last 'S'
//   'Q'  -> one JSON line of totals; the harness exits
// A transaction that is not answered within 1 << 24 cycles ends the harness with exit 6.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <vector>

#include "verilated.h"
#include "Vaxi.h"

#ifndef CUNEATE_WRITE_FIELD_BITS
#error "CUNEATE_WRITE_FIELD_BITS must be defined"
#endif

static const int FIELD = CUNEATE_WRITE_FIELD_BITS;
static const uint64_t PATIENCE = 1ull << 24;

static bool read_exact(void* p, size_t n) { return fread(p, 1, n, stdin) == n; }
static void write_all(const void* p, size_t n) {
    if (fwrite(p, 1, n, stdout) != n) exit(3);
}

struct Beat {
    uint64_t data;
    uint8_t flags;
};

struct Bus {
    Vaxi* top;
    uint64_t cycle = 0, sweeps = 0, beats_in = 0, beats_out = 0, spike_beats = 0;
    uint64_t reg_writes = 0, reg_reads = 0;
    std::vector<Beat> got;

    // one clock cycle with the inputs as set; returns after the rising edge
    void cycle_once(bool* s_take, bool* aw, bool* w, bool* b, bool* ar, bool* r) {
        top->m_axis_tready = 1;
        top->clk = 0;
        top->eval();
        if (s_take) *s_take = top->s_axis_tvalid && top->s_axis_tready;
        if (aw) *aw = top->s_axil_awvalid && top->s_axil_awready;
        if (w) *w = top->s_axil_wvalid && top->s_axil_wready;
        if (b) *b = top->s_axil_bvalid && top->s_axil_bready;
        if (ar) *ar = top->s_axil_arvalid && top->s_axil_arready;
        if (r) *r = top->s_axil_rvalid && top->s_axil_rready;
        if (top->m_axis_tvalid) {
            uint8_t flags = (top->m_axis_tlast ? 1 : 0) | (top->m_axis_tuser ? 2 : 0);
            got.push_back({(uint64_t)top->m_axis_tdata, flags});
            beats_out++;
            if (top->m_axis_tlast) sweeps++;
            if (!top->m_axis_tuser) spike_beats++;
        }
        top->clk = 1;
        top->eval();
        cycle++;
    }

    void idle() { cycle_once(nullptr, nullptr, nullptr, nullptr, nullptr, nullptr); }

    void burst(const std::vector<std::pair<uint32_t, int32_t>>& vals) {
        uint64_t mask = FIELD >= 64 ? ~0ull : ((1ull << FIELD) - 1);
        for (size_t i = 0; i < vals.size(); i++) {
            uint64_t v = (uint64_t)(int64_t)vals[i].second & mask;
            top->s_axis_tdata = v | ((uint64_t)vals[i].first << FIELD);
            top->s_axis_tlast = i + 1 == vals.size();
            top->s_axis_tvalid = 1;
            bool take = false;
            for (uint64_t c = 0; !take; c++) {
                if (c > PATIENCE) exit(6);
                cycle_once(&take, nullptr, nullptr, nullptr, nullptr, nullptr);
            }
            beats_in++;
        }
        top->s_axis_tvalid = 0;
        top->s_axis_tlast = 0;
    }

    // an AXI4-Lite transaction's cycles until its response is taken (`taken`, which `cycle`
    // sets): each cycle `sample` reads the response with the clock low (with the handshake's
    // edge to come), then `cycle` runs the cycle and drops the request's valids once taken
    template <class Sample, class Cycle>
    void until_response(const bool& taken, Sample sample, Cycle cycle) {
        for (uint64_t c = 0; !taken; c++) {
            if (c > PATIENCE) exit(6);
            top->clk = 0;
            top->eval();
            sample();
            cycle();
        }
    }

    uint8_t axil_write(uint32_t addr, uint32_t data) {
        top->s_axil_awaddr = addr;
        top->s_axil_wdata = data;
        top->s_axil_wstrb = 0xF;
        top->s_axil_awvalid = 1;
        top->s_axil_wvalid = 1;
        top->s_axil_bready = 1;
        bool b = false;
        uint8_t resp = 0;
        until_response(b, [&] { resp = top->s_axil_bresp; }, [&] {
            bool aw, w;
            cycle_once(nullptr, &aw, &w, &b, nullptr, nullptr);
            if (aw) top->s_axil_awvalid = 0;
            if (w) top->s_axil_wvalid = 0;
        });
        top->s_axil_bready = 0;
        reg_writes++;
        return resp;
    }

    uint32_t axil_read(uint32_t addr, uint8_t* resp) {
        top->s_axil_araddr = addr;
        top->s_axil_arvalid = 1;
        top->s_axil_rready = 1;
        bool r = false;
        uint32_t data = 0;
        until_response(r, [&] {
            data = top->s_axil_rdata;
            *resp = top->s_axil_rresp;
        }, [&] {
            bool ar;
            cycle_once(nullptr, nullptr, nullptr, nullptr, &ar, &r);
            if (ar) top->s_axil_arvalid = 0;
        });
        top->s_axil_rready = 0;
        reg_reads++;
        return data;
    }
};

int main(int argc, char** argv) {
    Verilated::commandArgs(argc, argv);
    Vaxi* top = new Vaxi;
    Bus bus;
    bus.top = top;
    top->rst = 1;
    for (int i = 0; i < 4; i++) bus.idle();
    bus.sweeps = bus.beats_out = bus.spike_beats = 0;
    bus.got.clear();
    top->rst = 0;
    std::vector<std::pair<uint32_t, int32_t>> vals;
    for (;;) {
        int op = fgetc(stdin);
        if (op == EOF || op == 'Q') break;
        if (op == 'W') {
            uint32_t n;
            if (!read_exact(&n, 4)) return 5;
            vals.resize(n);
            for (uint32_t i = 0; i < n; i++) {
                if (!read_exact(&vals[i].first, 4) || !read_exact(&vals[i].second, 4)) return 5;
            }
            bus.burst(vals);
            write_all(&bus.cycle, 8);
        } else if (op == 'L') {
            uint32_t addr, data;
            if (!read_exact(&addr, 4) || !read_exact(&data, 4)) return 5;
            uint8_t resp = bus.axil_write(addr, data);
            write_all(&resp, 1);
            write_all(&bus.cycle, 8);
        } else if (op == 'R') {
            uint32_t addr;
            if (!read_exact(&addr, 4)) return 5;
            uint8_t resp = 0;
            uint32_t data = bus.axil_read(addr, &resp);
            write_all(&data, 4);
            write_all(&resp, 1);
            write_all(&bus.cycle, 8);
        } else if (op == 'S') {
            uint64_t target, max_cycles;
            if (!read_exact(&target, 8) || !read_exact(&max_cycles, 8)) return 5;
            uint8_t why = 2;
            for (uint64_t c = 0; c < max_cycles; c++) {
                if (bus.sweeps >= target) { why = 0; break; }
                bus.idle();
            }
            if (bus.sweeps >= target) why = 0;
            uint32_t m = (uint32_t)bus.got.size();
            write_all(&m, 4);
            for (const Beat& b : bus.got) {
                write_all(&b.data, 8);
                write_all(&b.flags, 1);
            }
            bus.got.clear();
            write_all(&bus.cycle, 8);
            write_all(&why, 1);
        } else {
            return 4;
        }
        fflush(stdout);
    }
    printf("{\"cycles\": %llu, \"beats_to_device\": %llu, \"beats_from_device\": %llu, "
           "\"spike_beats\": %llu, \"sweeps\": %llu, \"register_writes\": %llu, "
           "\"register_reads\": %llu}\n", (unsigned long long)bus.cycle,
           (unsigned long long)bus.beats_in, (unsigned long long)bus.beats_out,
           (unsigned long long)bus.spike_beats, (unsigned long long)bus.sweeps,
           (unsigned long long)bus.reg_writes, (unsigned long long)bus.reg_reads);
    fflush(stdout);
    top->final();
    delete top;
    return 0;
}
