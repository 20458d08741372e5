// Compiled run of the generated Izhikevich core, or of an array of cores: no Python per cycle.
//
// Built by Verilator together with the Verilog (class Vtop): a core (`izhikevich_core`), or,
// with CUNEATE_CORES = K > 1, an `izhikevich_array` of K cores built with probes, whose per-core
// update ports `p<k>_*` the generated `array_probes.inc` reads (one PROBE(k) per core). Neuron
// ids are global (core k holds k * n .. (k + 1) * n - 1); ticks come every n = N / K cycles.
// Usage:
//
//     harness <schedule.bin> <out_dir> [--dump] [--raw CYCLES]
//
// schedule.bin (little-endian int64): N, n_sweeps, n_segments, v_width, u_width, i_width,
// then per segment: start_sweep followed by N raw currents. Before the first sweep of each
// segment the pipeline is drained and every current that changed is written by the host port
// (one per cycle), so each sweep sees exactly the currents of its segment - the twin's
// set_currents() before sweep(). Ticks come every N cycles (one update per clock).
//
// Outputs in out_dir:
//   spikes.bin   int64 pairs (sweep, neuron) from the update port, in update order
//   updates.bin  (--dump) per update: int64 v, u, current, spike, clamp bits
//   summary.json cycles, wall time, cycles/s, spike and stream counts, clamp counters summed
//                over sweep_done, sticky flags, overrun and spike_overflow
// --raw CYCLES: only reset and run the core free for CYCLES cycles with ticks (Verilator's
// raw cycle rate for this design, nothing recorded) and write summary.json.
#include "batch_harness.h"

#ifndef CUNEATE_CORES
#define CUNEATE_CORES 1
#endif
static const int CORES = CUNEATE_CORES;
// an array registers the tick and the host writes once more on their way to its cores
static const int ARRAY_EXTRA = CUNEATE_CORES > 1 ? 2 : 0;

// the core's pipeline depth (pipeline_stages), set by the build
#ifndef CUNEATE_PIPELINE_DEPTH
#define CUNEATE_PIPELINE_DEPTH 5
#endif
static const int PIPELINE_DEPTH = CUNEATE_PIPELINE_DEPTH;

static int64_t sext(uint64_t x, int width) {
    uint64_t m = 1ULL << (width - 1);
    x &= (width == 64) ? ~0ULL : ((1ULL << width) - 1);
    return (int64_t)((x ^ m) - m);
}

int main(int argc, char** argv) {
    if (argc < 3) die("usage: harness <schedule.bin> <out_dir> [--dump] [--raw CYCLES]");
    std::string sched_path = argv[1], out_dir = argv[2];
    bool dump = false;
    long long raw_cycles = -1;
    for (int a = 3; a < argc; ++a) {
        if (!std::strcmp(argv[a], "--dump")) dump = true;
        else if (!std::strcmp(argv[a], "--raw") && a + 1 < argc) raw_cycles = std::atoll(argv[++a]);
        else die("unknown argument");
    }
    int64_t hdr[6];
    FILE* f = open_schedule(sched_path, hdr, 6);
    const int64_t N = hdr[0], n_sweeps = hdr[1], n_seg = hdr[2];
    const int vw = (int)hdr[3], uw = (int)hdr[4], iw = (int)hdr[5];
    if (N < 1 || n_sweeps < 0 || n_seg < 0 || vw < 1 || vw > 64 || uw < 1 || uw > 64 || iw < 1 ||
        iw > 64)
        die("bad schedule header");
    std::vector<int64_t> seg_start(n_seg);
    std::vector<int64_t> seg_cur(n_seg * N);
    for (int64_t s = 0; s < n_seg; ++s) {
        if (!read_values(f, &seg_start[s], 1) || !read_values(f, &seg_cur[s * N], N))
            die("short schedule");
    }
    std::fclose(f);

    Clocked h(argv);
    Vtop* top = h.top.get();
    if (N % CORES) die("N must be a multiple of the cores");
    const int64_t n_core = N / CORES;   // neurons of each core: one sweep every n_core cycles
    const uint64_t imask = (iw == 64) ? ~0ULL : ((1ULL << iw) - 1);

    auto cycle = [&]() { h.cycle(); };
    // reset
    top->i_wr_en = 0;
    top->sel_wr_en = 0;
    top->clamp_clear = 0;
    top->tick = 0;
    top->spike_ready = 1;
    h.leave_reset();

    FILE* fs = nullptr;
    FILE* fu = nullptr;
    if (raw_cycles < 0) {
        fs = open_output(out_dir, "spikes.bin");
        if (dump) fu = open_output(out_dir, "updates.bin");
    }
    std::vector<int64_t> spk;
    spk.reserve(1 << 16);
    std::vector<int64_t> upd;
    if (dump) upd.reserve(5 * 65536);
    long long n_spikes = 0, stream_spikes = 0, updates = 0, sweeps_done = 0;
    long long clamp_counts[5] = {0, 0, 0, 0, 0};
    int64_t upd_sweep[CUNEATE_CORES] = {0};   // per core, sweep of its next update

    // one update leaving core k's pipeline (local index)
    auto on_update = [&](int k, int64_t local, bool spike, uint64_t v, uint64_t u,
                         uint64_t current, unsigned clamp) {
        int64_t idx = k * n_core + local;
        if (spike) {
            spk.push_back(upd_sweep[k]);
            spk.push_back(idx);
            ++n_spikes;
            spill(spk, fs, 1u << 16);
        }
        if (dump) {
            upd.push_back(sext(v, vw));
            upd.push_back(sext(u, uw));
            upd.push_back(sext(current, iw));
            upd.push_back(spike);
            upd.push_back(clamp);
            spill(upd, fu, 5 * 65536);
        }
        ++updates;
        if (local == n_core - 1) ++upd_sweep[k];
#if CUNEATE_CORES > 1
        for (int b = 0; b < 5; ++b) clamp_counts[b] += (clamp >> b) & 1;
#endif
    };

    auto monitor = [&]() {
#if CUNEATE_CORES > 1
#define PROBE(k)                                                                            \
        if (top->p##k##_valid)                                                              \
            on_update(k, (int64_t)top->p##k##_index, top->p##k##_spike, top->p##k##_v,      \
                      top->p##k##_u, top->p##k##_current, top->p##k##_clamp);
#include "array_probes.inc"
#undef PROBE
        if (top->sweep_done) ++sweeps_done;
#else
        if (top->upd_valid)
            on_update(0, (int64_t)top->upd_index, top->upd_spike, top->upd_v, top->upd_u,
                      top->upd_current, top->upd_clamp);
        if (top->sweep_done) {
            ++sweeps_done;
            clamp_counts[0] += top->sweep_clamps_v_low;
            clamp_counts[1] += top->sweep_clamps_u_high;
            clamp_counts[2] += top->sweep_clamps_u_low;
            clamp_counts[3] += top->sweep_clamps_current;
            clamp_counts[4] += top->sweep_clamps_y;
        }
#endif
        if (top->spike_valid) ++stream_spikes;
    };
    // n cycles, each monitored
    auto step = [&](int64_t n) {
        for (int64_t k = 0; k < n; ++k) {
            cycle();
            monitor();
        }
    };
    h.start_clock();
    if (raw_cycles >= 0) {
        for (long long c = 0; c < raw_cycles; ++c) {
            top->tick = (c % n_core) == 0;
            cycle();
        }
    } else {
        std::vector<int64_t> cur(N, 0);   // the current RAM starts at zero
        int64_t sweep = 0;
        int64_t seg = 0;
        while (sweep < n_sweeps || seg < n_seg) {
            if (seg < n_seg && seg_start[seg] <= sweep) {
                // drain the pipeline, then write the currents that change
                top->tick = 0;
                step(PIPELINE_DEPTH + 2 + ARRAY_EXTRA);
                for (int64_t n = 0; n < N; ++n) {
                    int64_t x = seg_cur[seg * N + n];
                    if (x == cur[n]) continue;
                    cur[n] = x;
                    top->i_wr_en = 1;
                    top->i_wr_addr = n;
                    top->i_wr_data = (uint64_t)x & imask;
                    step(1);
                }
                top->i_wr_en = 0;
                step(ARRAY_EXTRA);
                ++seg;
                continue;
            }
            if (sweep >= n_sweeps) break;
            // run sweeps up to the next segment
            int64_t end = (seg < n_seg) ? std::min<int64_t>(seg_start[seg], n_sweeps) : n_sweeps;
            for (; sweep < end; ++sweep) {
                top->tick = 1;
                step(1);
                top->tick = 0;
                step(n_core - 1);
            }
        }
        top->tick = 0;
        // drain the pipeline (and an array's spike stream, one spike a cycle)
        for (int64_t k = 0; k < PIPELINE_DEPTH + 4 + ARRAY_EXTRA ||
                            (CORES > 1 && top->spike_valid && k < 2 * N + 16); ++k) {
            cycle();
            monitor();
        }
    }
    double wall = h.wall_s();
    if (fs) {
        spill(spk, fs);
        std::fclose(fs);
    }
    if (fu) {
        spill(upd, fu);
        std::fclose(fu);
    }
    unsigned sticky = top->clamp_flags;
    FILE* fj = open_output(out_dir, "summary.json", "w");
    std::fprintf(fj,
                 "{\"cycles\": %lld, \"wall_s\": %.9f, \"cycles_per_s\": %.3f, \"updates\": %lld, "
                 "\"sweeps_done\": %lld, \"spikes\": %lld, \"stream_spikes\": %lld, "
                 "\"clamp_counts\": {\"v_low\": %lld, \"u_high\": %lld, \"u_low\": %lld, "
                 "\"current\": %lld, \"y\": %lld}, \"clamp_sticky_bits\": %u, \"overrun\": %d, "
                 "\"spike_overflow\": %d, \"raw\": %s}\n",
                 h.cycles, wall, wall > 0 ? h.cycles / wall : 0.0, updates, sweeps_done, n_spikes,
                 stream_spikes, clamp_counts[0], clamp_counts[1], clamp_counts[2], clamp_counts[3],
                 clamp_counts[4], sticky, (int)top->overrun, (int)top->spike_overflow,
                 raw_cycles >= 0 ? "true" : "false");
    std::fclose(fj);
    top->final();
    return 0;
}
