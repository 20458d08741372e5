// The board top compiled by Verilator behind a simulated serial line (the `board` engine).
//
// The top has the pins of the board's UART (`rx` in, `tx` out) and its clock and reset; the
// harness is the far end of the line: it drives `rx` with the host's bytes as 8N1 frames of
// CUNEATE_CLOCKS_PER_BIT cycles a bit (start bit low, eight data bits LSB first, stop bit high,
// back to back) and decodes `tx` the same way (sampled mid-bit; a byte whose stop bit is low is
// a framing error: counted, not delivered). The clocks per bit are the gateware's own
// (`LinkConfig.clocks_per_bit`): both ends of the line run at the same rate.
//
// Protocol on stdin/stdout (little-endian binary), one request, one answer:
//   request  'R' u32 n, n bytes (appended to the line toward the device),
//            u64 gap, u64 quiet, u64 max_cycles
//   answer   u32 m, m bytes (decoded from tx), u64 cycle, u8 why
// The harness runs until, in this order of checks each cycle:
//   why = 0: it has decoded at least one byte and `tx` has stayed idle for `gap` cycles since
//            the last stop bit (a frame, usually whole, has arrived);
//   why = 1: nothing is left to send on `rx` and no byte has come for `quiet` cycles since the
//            last byte either way (the device has nothing more to say);
//   why = 2: `max_cycles` cycles have run in this request.
//   request  'Q': the harness writes its totals as one JSON line on stdout and exits.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <vector>

#include "verilated.h"
#include "Vboard.h"

#ifndef CUNEATE_CLOCKS_PER_BIT
#error "CUNEATE_CLOCKS_PER_BIT must be defined"
#endif

static const uint64_t CPB = CUNEATE_CLOCKS_PER_BIT;

static bool read_exact(void* p, size_t n) { return fread(p, 1, n, stdin) == n; }
static void write_all(const void* p, size_t n) {
    if (fwrite(p, 1, n, stdout) != n) exit(3);
}

struct Line {
    Vboard* top;
    uint64_t cycle = 0;
    // host -> device
    std::deque<uint8_t> out;
    int tx_bit = -1;          // bit index of the byte being sent (-1: idle), 0 = start
    uint64_t tx_left = 0;     // cycles left in the current bit
    uint8_t tx_byte = 0;
    // device -> host
    int rx_state = 0;         // 0 idle, 1 in a byte
    uint64_t rx_wait = 0;     // cycles to the next sample
    int rx_bit = 0;
    uint8_t rx_byte = 0;
    uint64_t since_byte = 0;  // cycles since the last byte either way
    uint64_t since_stop = 0;  // cycles since the last decoded stop bit
    uint64_t bytes_in = 0, bytes_out = 0, framing_errors = 0;

    void drive() {
        if (tx_bit < 0 && !out.empty()) {
            tx_byte = out.front();
            out.pop_front();
            tx_bit = 0;
            tx_left = CPB;
        }
        if (tx_bit < 0) {
            top->rx = 1;
        } else if (tx_bit == 0) {
            top->rx = 0;
        } else if (tx_bit <= 8) {
            top->rx = (tx_byte >> (tx_bit - 1)) & 1;
        } else {
            top->rx = 1;
        }
    }

    void after_cycle(std::vector<uint8_t>& got) {
        if (tx_bit >= 0 && --tx_left == 0) {
            if (++tx_bit == 10) {
                tx_bit = -1;
                bytes_in++;
                since_byte = 0;
            } else {
                tx_left = CPB;
            }
        }
        int pin = top->tx;
        if (rx_state == 0) {
            if (!pin) {                       // a start bit: sample mid-bit from here
                rx_state = 1;
                rx_bit = 0;
                rx_byte = 0;
                rx_wait = CPB / 2 + CPB;
            }
        } else if (--rx_wait == 0) {
            if (rx_bit < 8) {
                rx_byte |= (uint8_t)(pin << rx_bit);
                rx_bit++;
                rx_wait = CPB;
            } else {                          // the stop bit
                if (pin) {
                    got.push_back(rx_byte);
                    bytes_out++;
                } else {
                    framing_errors++;
                }
                rx_state = 0;
                since_byte = 0;
                since_stop = 0;
                return;
            }
        }
        since_byte++;
        since_stop++;
    }

    void tick(std::vector<uint8_t>& got) {
        drive();
        top->clk = 0;
        top->eval();
        top->clk = 1;
        top->eval();
        cycle++;
        after_cycle(got);
    }
};

int main(int argc, char** argv) {
    Verilated::commandArgs(argc, argv);
    Vboard* top = new Vboard;
    Line line;
    line.top = top;
    top->rx = 1;
    top->rst = 1;
    for (int i = 0; i < 4; i++) {
        top->clk = 0;
        top->eval();
        top->clk = 1;
        top->eval();
    }
    top->rst = 0;
    std::vector<uint8_t> got, buf;
    for (;;) {
        int op = fgetc(stdin);
        if (op == EOF || op == 'Q') break;
        if (op != 'R') return 4;
        uint32_t n;
        uint64_t gap, quiet, max_cycles;
        if (!read_exact(&n, 4)) return 5;
        buf.resize(n);
        if (n && !read_exact(buf.data(), n)) return 5;
        if (!read_exact(&gap, 8) || !read_exact(&quiet, 8) || !read_exact(&max_cycles, 8))
            return 5;
        for (uint8_t b : buf) line.out.push_back(b);
        if (n) line.since_byte = 0;
        got.clear();
        uint8_t why = 2;
        for (uint64_t c = 0; c < max_cycles; c++) {
            line.tick(got);
            if (!got.empty() && line.rx_state == 0 && line.since_stop >= gap) { why = 0; break; }
            if (got.empty() && line.out.empty() && line.tx_bit < 0 && line.rx_state == 0 &&
                line.since_byte >= quiet) { why = 1; break; }
        }
        uint32_t m = (uint32_t)got.size();
        write_all(&m, 4);
        if (m) write_all(got.data(), m);
        write_all(&line.cycle, 8);
        write_all(&why, 1);
        fflush(stdout);
    }
    printf("{\"cycles\": %llu, \"bytes_to_device\": %llu, \"bytes_from_device\": %llu, "
           "\"framing_errors\": %llu}\n", (unsigned long long)line.cycle,
           (unsigned long long)line.bytes_in, (unsigned long long)line.bytes_out,
           (unsigned long long)line.framing_errors);
    fflush(stdout);
    top->final();
    delete top;
    return 0;
}
