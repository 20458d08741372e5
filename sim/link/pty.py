"""A simulated board on a pseudo-terminal: :class:`PtyBoard` serves the board top (the link and
the core, compiled by Verilator behind its UART: :class:`~cuneate.sim.link.engines
.VerilatorSerial`) on the master side of a pty pair, so that any host software that opens a
serial device (pyserial, ``cuneate stream BOARD --port PATH``, a terminal program) talks to the
gateware a board runs, byte for byte, without the board.

The simulation runs in lockstep with the host, as the ``board`` engine's does: a background
thread relays the host's bytes into the simulated line and runs the simulation while the
device may still answer (bytes to send, or no quiet spell yet since the host last wrote), writing
every byte the device sends back to the master (after a frame it gives the host a moment to
reply before it simulates on); once the device has fallen quiet it waits in ``select`` for the
host's next bytes (no busy loop). The simulated clock therefore stands still between the
host's requests, which a lockstep host (:class:`~cuneate.sim.host.uart.UartTransport`) never
notices; a free-running core (``START``) runs as fast as Verilator goes. If the harness ends,
the relay closes the master (the host's next read fails at once: the line hung up) and
:meth:`PtyBoard.close` raises :class:`PtyBoardError` naming why.

Run ``python -m cuneate.sim.link.pty [SCENE]`` to serve the board for a scene's core (the
default scene without one) until interrupted: it prints the device path to give to
``cuneate stream BOARD --port PATH SCENE``.
"""

from __future__ import annotations

import argparse
import errno
import fcntl
import os
import select
import signal
import threading
import time
import tty
from pathlib import Path

from ...hdl.link import LinkConfig
from ..network.scene import scene_layer
from ..scenes.afferent import build_neurons, core_config, n_driven, scene_channel_plan
from ..scenes.scene import default_scene, example_path, load_scene
from .engines import BOARD_CLOCKS_PER_BIT, VerilatorSerial, board_link

__all__ = ["PtyBoard", "PtyBoardError", "scene_link", "main"]


class PtyBoardError(RuntimeError):
    """The simulated board stopped serving: its harness ended or the pty failed."""


class PtyBoard:
    """The board top in Verilator, served on a pseudo-terminal.

    Parameters
    ----------
    config
        The block (a configuration or payload spec: the link is sized to it as the ``board``
        engine sizes it, :func:`~cuneate.sim.link.engines.board_link`) or the link itself (a
        :class:`~cuneate.hdl.link.LinkConfig`); the board top is its
        :class:`~cuneate.hdl.link.LinkedTop`.
    clocks_per_bit
        Clocks per UART bit on the simulated line (for a block's configuration).
    build_root
        Where compiled harnesses are cached (default: the ``verilator-fast`` cache).
    poll_s
        How long the relay waits in ``select`` while the device is quiet before checking
        whether it was closed.
    reply_s
        How long the relay waits for the host's reply to the device's bytes before it runs the
        simulation on (a lockstep host replies at once; without the pause the device would
        run out its quiet spell first: simulated cycles that change nothing but cost time).

    Attributes
    ----------
    path
        The slave device's path (``/dev/pts/N``): what the host opens.
    serial
        The :class:`~cuneate.sim.link.engines.VerilatorSerial` behind the pty.
    bytes_to_device, bytes_to_host
        Bytes relayed from the host into the simulated line, and from the device to the host.
    error
        Why the relay stopped, when it stopped by itself (``None`` while it serves, and after a
        plain :meth:`close`).
    """

    def __init__(self, config, clocks_per_bit: int = BOARD_CLOCKS_PER_BIT, build_root=None,
                 poll_s: float = 0.05, reply_s: float = 0.002):
        self.lcfg = config if isinstance(config, LinkConfig) else \
            board_link(config, clocks_per_bit)
        self.poll_s, self.reply_s = poll_s, reply_s
        self.serial = VerilatorSerial(self.lcfg, build_root=build_root)
        self.bytes_to_device = 0
        self.bytes_to_host = 0
        self.error: BaseException | None = None
        try:
            self._master, self._slave = os.openpty()
            tty.setraw(self._slave)
            fl = fcntl.fcntl(self._master, fcntl.F_GETFL)
            fcntl.fcntl(self._master, fcntl.F_SETFL, fl | os.O_NONBLOCK)
            self.path = os.ttyname(self._slave)
            self._wake_r, self._wake_w = os.pipe()
        except OSError:                         # no pty to serve on: the harness goes too
            self.serial.close()
            raise
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name=f"pty board {self.path}",
                                        daemon=True)
        self._thread.start()

    # -- the relay ---------------------------------------------------------------------------
    def _serve(self) -> None:
        try:
            self._relay()
        except BaseException as exc:            # reported by close(); the host sees a hangup
            self.error = exc
        finally:
            self._close_master()

    def _relay(self) -> None:
        serial, master = self.serial, self._master
        to_host = bytearray()
        answered = False                # the device has just sent bytes: the host may reply
        while not self._stop.is_set():
            if serial.silent:
                wait = self.poll_s
            elif answered:              # a lockstep host answers a frame at once: let it,
                wait = self.reply_s     # rather than simulate the device's quiet meanwhile
            else:
                wait = 0.0
            readable, writable, _ = select.select([master, self._wake_r],
                                                  [master] if to_host else [], [], wait)
            if self._wake_r in readable:
                return
            if master in readable:
                data = self._read_master()
                if data:
                    serial.write(data)
                    self.bytes_to_device += len(data)
            if master in writable:
                self._write_master(to_host)
            answered = False
            if not serial.silent:
                serial.advance()
                if serial.in_waiting:
                    to_host += serial.read(serial.in_waiting)
                    self._write_master(to_host)
                    answered = True

    def _write_master(self, to_host: bytearray) -> None:
        """Write what the master takes of ``to_host`` now; the rest stays in it."""
        if not to_host:
            return
        try:
            n = os.write(self._master, to_host)
        except BlockingIOError:
            n = 0
        del to_host[:n]
        self.bytes_to_host += n

    def _read_master(self) -> bytes:
        try:
            return os.read(self._master, 4096)
        except BlockingIOError:
            return b""
        except OSError as exc:
            if exc.errno == errno.EIO:       # no slave open (cannot happen while we hold one)
                return b""
            raise

    def _close_master(self) -> None:
        if self._master is not None:
            os.close(self._master)
            self._master = None

    # -- life cycle --------------------------------------------------------------------------
    @property
    def serving(self) -> bool:
        """The relay is running."""
        return self._thread.is_alive()

    def close(self, timeout_s: float = 10.0) -> None:
        """Stop the relay and the harness; raise :class:`PtyBoardError` when the relay had
        stopped by itself (the harness ended, the pty failed), naming why."""
        if self._stop.is_set():
            return
        self._stop.set()
        os.write(self._wake_w, b"x")
        self._thread.join(timeout_s)
        if self._thread.is_alive():          # inside a long simulation request: end it
            self.serial.kill()
            self._thread.join(timeout_s)
        try:
            self.serial.close()
        except OSError:                       # the harness already gone
            pass
        for fd in (self._slave, self._wake_r, self._wake_w):
            os.close(fd)
        if self.error is not None:
            raise PtyBoardError(f"the simulated board on {self.path} stopped: "
                                f"{type(self.error).__name__}: {self.error}") from self.error

    @property
    def totals(self) -> dict:
        """Bytes relayed each way, cycles simulated and the harness's own line totals (after
        :meth:`close`)."""
        return {"bytes_to_device": self.bytes_to_device, "bytes_to_host": self.bytes_to_host,
                "cycles": self.serial.cycles, "line": dict(self.serial.totals)}

    def __enter__(self) -> "PtyBoard":
        return self

    def __exit__(self, *exc) -> bool:
        self.close()
        return False


def scene_link(scene, clocks_per_bit: int = BOARD_CLOCKS_PER_BIT):
    """The board an afferent scene streams to, as the ``board`` engine sizes it (what
    :class:`PtyBoard` serves), holding the scene's trials or ``hardware.board_trials`` of them
    as ``cuneate build`` does: the link of its core, or with a cuneate layer of the
    afferent -> cuneate network, behind the scene's channel fan-out with
    ``hardware.fanout``."""
    k = scene["hardware"]["board_trials"] or n_driven(scene)[0]
    neurons = build_neurons(scene, k)
    cfg = core_config(scene, k)
    fan = scene_channel_plan(scene).config.first(len(neurons)) if scene["hardware"]["fanout"] \
        else None
    layer = scene_layer(scene, neurons, cfg)
    block = cfg if layer is None else layer.network
    return board_link(block, clocks_per_bit, fanout=fan)


def main(argv=None) -> int:
    """Serve the board for a scene's core (a scene file or shipped example name; the default
    scene without one) on a pty until interrupted."""
    p = argparse.ArgumentParser(prog="python -m cuneate.sim.link.pty",
                                description="serve a simulated board on a pseudo-terminal")
    p.add_argument("scene", nargs="?", default=None,
                   help="scene file or shipped example name (default: the default scene)")
    args = p.parse_args(argv)
    if args.scene is None:
        scene = default_scene()
    elif Path(args.scene).is_file():
        scene = load_scene(Path(args.scene))
    elif example_path(args.scene) is not None:
        scene = load_scene(example_path(args.scene))
    else:
        p.error(f"scene {args.scene!r}: no such file or shipped example")
    if scene.kind != "afferent":
        p.error(f"{scene.source} is a {scene.kind} scene; a board streams afferent scenes")
    board = PtyBoard(scene_link(scene))
    print(f"serving {scene.name!r} ({board.lcfg.n_neurons} neurons) on {board.path}; "
          f"Ctrl-C ends", flush=True)

    def interrupt(signum, frame):
        raise KeyboardInterrupt
    signal.signal(signal.SIGTERM, interrupt)        # a service manager's stop: the same end
    try:
        while board.serving:
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    try:
        board.close()
    except PtyBoardError as exc:
        print(exc)
        return 1
    t = board.totals
    print(f"relayed {t['bytes_to_device']} bytes to the device, {t['bytes_to_host']} to the "
          f"host; {t['cycles']} cycles")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
