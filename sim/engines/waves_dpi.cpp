// The end of a waveform window on Verilator (see cuneate/sim/engines/waves.py).
//
// Verilator opens a trace on $dumpvars but ignores $dumpoff; the window's control block calls
// this DPI function after the window's last tick instead, and it closes the model's trace (the
// same call the model makes when it is destroyed), so nothing more is written. Compiled into
// the cocotb model of a core (cocotb builds with --prefix Vtop).
#include "svdpi.h"
#include "verilated.h"
#include "Vtop__Syms.h"

extern "C" void cuneate_waves_close() {
    const VerilatedScope* scope = static_cast<const VerilatedScope*>(svGetScope());
    if (scope == nullptr) return;
    Vtop__Syms* syms = static_cast<Vtop__Syms*>(scope->symsp());
    if (syms->__Vm_dumping) syms->_traceDumpClose();
}
