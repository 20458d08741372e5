// Compiled run of the generated learning layer (`learning_layer`, class Vtop): presentations
// of afferent spikes, each followed by its window's end, no Python per cycle.
//
//     harness <schedule.bin> <out_dir> [--snap N]
//
// schedule.bin (little-endian int64): M, K, S, n_pres, n_ticks, window_ticks, n_events,
// then offsets (n_pres + 1), learn flags (n_pres), event ticks (n_events), event sources
// (n_events). Presentation p's events are offsets[p] .. offsets[p+1]-1, tick-major. Per tick
// the events are driven one a cycle (in_valid / in_source), then one tick pulse, then the
// layer runs until idle; after a presentation's n_ticks ticks a learn pulse (learn_apply =
// its flag) and the layer runs until learn_done.
//
// Outputs in out_dir:
//   spikes.bin   int64 triples (presentation, tick in the presentation, CN) from the stream
//   weights.bin  int64 weights read back through the host port, M * K per snapshot: every
//                N presentations with --snap N (and always after the last)
//   summary.json cycles, wall time, cycles/s, counters, clamp counts per kind
#include "batch_harness.h"

int main(int argc, char** argv) {
    if (argc < 3) die("usage: harness <schedule.bin> <out_dir> [--snap N]");
    std::string sched_path = argv[1], out_dir = argv[2];
    long long snap = 0;
    for (int a = 3; a < argc; ++a) {
        if (!std::strcmp(argv[a], "--snap") && a + 1 < argc) snap = std::atoll(argv[++a]);
        else die("unknown argument");
    }
    int64_t hdr[7];
    FILE* f = open_schedule(sched_path, hdr, 7);
    const int64_t M = hdr[0], K = hdr[1], S = hdr[2], n_pres = hdr[3], n_ticks = hdr[4],
                  win = hdr[5], n_ev = hdr[6];
    if (M < 1 || K < 1 || S < 1 || n_pres < 0 || n_ticks < 0 || win < 0 || n_ev < 0)
        die("bad schedule header");
    std::vector<int64_t> off(n_pres + 1), flags(n_pres), ev_t(n_ev), ev_s(n_ev);
    if (!read_values(f, off.data(), n_pres + 1) || !read_values(f, flags.data(), n_pres) ||
        !read_values(f, ev_t.data(), n_ev) || !read_values(f, ev_s.data(), n_ev))
        die("short schedule");
    std::fclose(f);

    Clocked h(argv);
    Vtop* top = h.top.get();
    long long stream = 0;
    std::vector<int64_t> spk;
    spk.reserve(1 << 16);
    FILE* fs = open_output(out_dir, "spikes.bin");
    FILE* fw = open_output(out_dir, "weights.bin");
    int64_t pres = 0, first_tick = 0;
    auto cycle = [&]() {
        h.cycle();
        if (top->spike_valid) {
            spk.push_back(pres);
            spk.push_back((int64_t)top->spike_tick - first_tick);
            spk.push_back((int64_t)top->spike_target);
            ++stream;
            spill(spk, fs, 3u << 16);
        }
    };
    auto settle = [&]() {
        cycle();
        cycle();
        while (top->busy) cycle();
        for (int i = 0; i < 6; ++i) cycle();
    };
    top->tick = 0;
    top->in_valid = 0;
    top->learn = 0;
    top->learn_apply = 0;
    top->w_wr_valid = 0;
    top->w_rd_valid = 0;
    top->clamp_clear = 0;
    h.leave_reset();
    std::vector<int64_t> wbuf(M * K);
    auto read_weights = [&]() {
        for (int64_t a = 0; a < M * K; ++a) {
            top->w_rd_valid = 1;
            top->w_rd_addr = a;
            cycle();
            top->w_rd_valid = 0;
            bool got = false;
            for (int i = 0; i < 5; ++i) {
                if (!got && top->w_rd_resp_valid) {
                    wbuf[a] = (int64_t)top->w_rd_resp_data;
                    got = true;
                }
                cycle();
            }
            if (!got) die("no response to a weight read");
        }
        std::fwrite(wbuf.data(), sizeof(int64_t), wbuf.size(), fw);
    };
    h.start_clock();
    for (pres = 0; pres < n_pres; ++pres) {
        first_tick = (int64_t)top->tick_count;
        int64_t e = off[pres];
        for (int64_t k = 0; k < n_ticks; ++k) {
            while (e < off[pres + 1] && ev_t[e] == k) {
                top->in_valid = 1;
                top->in_source = ev_s[e];
                cycle();
                ++e;
            }
            top->in_valid = 0;
            top->tick = 1;
            cycle();
            top->tick = 0;
            settle();
        }
        top->learn = 1;
        top->learn_apply = flags[pres] ? 1 : 0;
        cycle();
        top->learn = 0;
        settle();
        if (snap > 0 && (pres + 1) % snap == 0 && pres + 1 < n_pres) read_weights();
    }
    read_weights();
    double wall = h.wall_s();
    spill(spk, fs);
    std::fclose(fs);
    std::fclose(fw);
    FILE* fj = open_output(out_dir, "summary.json", "w");
    std::fprintf(fj,
                 "{\"cycles\": %lld, \"wall_s\": %.6f, \"cycles_per_s\": %.1f, "
                 "\"stream_spikes\": %lld, \"tick_count\": %lld, \"learn_count\": %lld, "
                 "\"merged_count\": %lld, \"overrun_count\": %lld, "
                 "\"learn_overrun_count\": %lld, \"hazard_count\": %lld, "
                 "\"clamp_counts\": [%lld, %lld, %lld, %lld, %lld, %lld, %lld, %lld, %lld]}\n",
                 h.cycles, wall, wall > 0 ? h.cycles / wall : 0.0, stream,
                 (long long)top->tick_count, (long long)top->learn_count,
                 (long long)top->merged_count, (long long)top->overrun_count,
                 (long long)top->learn_overrun_count, (long long)top->hazard_count,
                 (long long)top->clamp_count_v_low, (long long)top->clamp_count_u_high,
                 (long long)top->clamp_count_u_low, (long long)top->clamp_count_current,
                 (long long)top->clamp_count_y, (long long)top->clamp_count_drive_low,
                 (long long)top->clamp_count_drive_high, (long long)top->clamp_count_weight_low,
                 (long long)top->clamp_count_weight_high);
    std::fclose(fj);
    top->final();
    return 0;
}
