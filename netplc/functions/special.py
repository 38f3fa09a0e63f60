"""Special functions (manual group 3.6): the I/O-module functions, PID and ERCODE.

WRITE, READ, MVAMOD, MVASET, MVARD, ADCWR and ADCRD talk to CPU-165 I/O modules (MVA-02/03/08,
the UPU-TP ADC) over the PLC's internal bus. NetPlc has no such modules, so they load (a ported
program still runs) and raise FErr1 each time they execute, changing nothing else.
"""

from __future__ import annotations

from dataclasses import dataclass

from netplc.address import IO_BITS
from netplc.functions._util import Step, built, byte_get, fail, word_get, word_set
from netplc.functions.registry import Fon, FonContext, register
from netplc.memory import Memory

for _number, _name, _s, _d, _r in (
    (19, "WRITE", "M", "O", "O"),
    (20, "READ", "O", "M", "M"),
    (21, "MVAMOD", "M", "O", "O"),
    (22, "MVASET", "M", "O", None),
    (23, "MVARD", "O", "M", None),
    (98, "ADCWR", "O", "O", "O"),
    (99, "ADCRD", "M", "O", "O"),
):
    register(_number, _name, _s, _d, _r, hardware=True)(lambda ctx, fon: fail(ctx))


# --- ERCODE ----------------------------------------------------------------------------------------

BLINK_ON = 0.5  # seconds on, then off, per pulse: one pulse per second
BLINK_GAP = 2.0  # seconds dark between groups of pulses
EXTERNAL_IO_END = 0o2000


@register(58, "ERCODE", "M", "M")
@built
def ercode(mem: Memory, fon: Fon) -> Step:
    """Show the error code byte[S] on the external output bit D: N one-second pulses, then 2 s dark.

    While byte[S] is 0 the bit is 0. Each pulse is 0.5 s on and 0.5 s off, counted from the scan on
    which the code became non-zero (or changed). The manual's error condition ("S above 01777 or D
    below 04000") contradicts its own example (S = 04000, D = 01000); decided: FErr1, and nothing
    done, when S is not a data address or D is not an external I/O bit (00000-01777).
    """
    s, d = fon.s or 0, fon.d or 0
    if s < IO_BITS or d >= EXTERNAL_IO_END:
        return fail
    get = byte_get(mem, s)
    b = mem.bits
    shown = {"code": 0, "since": 0.0}

    def step(ctx: FonContext) -> None:
        code = get()
        if code != shown["code"]:
            shown["code"], shown["since"] = code, ctx.now
        if not code:
            b[d] = 0
            return
        t = (ctx.now - shown["since"] + 1e-9) % (code + BLINK_GAP)
        b[d] = 1 if t < code and t % 1.0 < BLINK_ON else 0

    return step


# --- PID -------------------------------------------------------------------------------------------

PID_AREA = 0o74000
PID_STRIDE = 0o100
PID_ERR_BITS = 0o3720
PID_K_BITS = 0o3730
PID_CTRL_BITS = 0o3740
PWM_MODE = 0o100
# regulator error word (074x50) bits
ERR_DIVISOR = 1  # a KP/TR/TD divisor is 0
ERR_LIMITS = 2  # XMIN > XMAX
ERR_QUANT = 4  # quantization unit is not 0
ERR_PWM = 8  # binary (PWM) control requested: it drives module outputs, not available here

# word offsets in a regulator's work area (bytes, octal as in the manual)
KP, KP_DIV, TR, TR_DIV, TD, TD_DIV, XMIN, XMAX, QUANT = 0o0, 0o2, 0o4, 0o6, 0o10, 0o12, 0o14, 0o16, 0o20
ITERM0, SETPOINT, SENSOR, FILTER, DEADZONE = 0o24, 0o26, 0o30, 0o34, 0o36
XOUT, ERROR, ITERM, ERRORS, ABS_ERROR = 0o40, 0o42, 0o44, 0o50, 0o52


def _signed16(v: float) -> int:
    """Two's-complement word of v, clamped to -32768..32767."""
    return int(max(-32768, min(32767, round(v)))) & 0xFFFF


@dataclass
class _Loop:
    """A regulator's history between executions (E1, E2, U1 and the exact integral)."""

    started: bool = False
    last: float = 0.0
    e1: float = 0.0
    e2: float = 0.0
    u1: float = 0.0
    iterm: float = 0.0


@register(41, "PID", "O", "O")
@built
def pid(mem: Memory, fon: Fon) -> Step:
    """PID regulators 0-7: bit x of S enables regulator x, D = formula 0-4 (+0100 = PWM control).

    Work area of regulator x at 074x00 (words, octal offsets): 00/02 KP and its divisor, 04/06 TR
    (seconds) and divisor, 10/12 TD (seconds) and divisor, 14/16 XMIN/XMAX, 20 quantization (must be
    0), 24 initial ITERM, 26 setpoint SV, 30 sensor PV, 34 filter, 36 dead zone; outputs 40 XOUT,
    42 error (signed), 44 ITERM (signed), 50 error word, 52 |error|.
    Formulas as printed in the manual (error = SV - PV; dterm = (error - E1)/dt):
      0: ITERM += error*dt;  XOUT = KP*error + KP*(ITERM/TR + dterm*TD)
      1: ITERM += error*dt;  XOUT = KP*error + ITERM/TR + dterm*TD
      2: XOUT = U1 + Q0*error + Q1*E1 + Q2*E2, Q0 = KP*(1 + dt/(2TR) + TD/dt),
         Q1 = -KP*(1 + 2TD/dt - dt/(2TR)), Q2 = KP*TD/dt
      3, 4: ITERM += KP*error*dt/TR;  XOUT = KP*error + KP*TD*dterm + ITERM
    Decided where the manual is silent:
    - dt is the engine time since the regulator's previous execution; the first execution (and
      the one after K, 03730+x, was set: K is then cleared) only initialises the history
      (ITERM from 074x24, E1 = E2 = error, U1 = XOUT) and writes error, |error| and ITERM;
    - TR = 0 means no integral action; the filter value 0 means no filter (as 100);
      |error| below the dead zone counts as 0;
    - XOUT is rounded and clamped to XMIN..XMAX; while it is clamped, the integral does not grow
      further in the clamped direction (anti-windup);
    - error word bits: 1 a divisor is 0, 2 XMIN > XMAX, 4 quantization unit not 0, 8 PWM control
      (it drives module outputs with minimum pulse lengths: not available on this platform);
      a regulator with errors does not compute, its Err bit (03720+x) is 1 and FErr1 is raised;
    - Ctrl (03740+x) = 1 while regulator x is enabled and computing, else 0.
    A formula number above 4 is a setup error: FErr1, nothing computed.
    """
    enable, formula, pwm = fon.s or 0, (fon.d or 0) & ~PWM_MODE, bool((fon.d or 0) & PWM_MODE)
    if formula > 4 or enable > 0xFF:
        return fail
    b = mem.bits
    regs = []
    reads = (KP, KP_DIV, TR, TR_DIV, TD, TD_DIV, XMIN, XMAX, QUANT, ITERM0, SETPOINT, SENSOR, FILTER,
             DEADZONE, XOUT)
    writes = (XOUT, ERROR, ITERM, ERRORS, ABS_ERROR)
    for x in range(8):
        base = PID_AREA + x * PID_STRIDE
        regs.append((x, {off: word_get(mem, base + off) for off in reads},
                     {off: word_set(mem, base + off) for off in writes}, _Loop()))

    def run_one(ctx: FonContext, x: int, g: dict, p: dict, loop: _Loop) -> None:
        errors = 0
        if 0 in (g[KP_DIV](), g[TR_DIV](), g[TD_DIV]()):
            errors |= ERR_DIVISOR
        xmin, xmax = g[XMIN](), g[XMAX]()
        if xmin > xmax:
            errors |= ERR_LIMITS
        if g[QUANT]():
            errors |= ERR_QUANT
        if pwm:
            errors |= ERR_PWM
        p[ERRORS](errors)
        b[PID_ERR_BITS + x] = 1 if errors else 0
        b[PID_CTRL_BITS + x] = 0 if errors else 1
        if errors:
            fail(ctx)
            return
        kp, tr, td = g[KP]() / g[KP_DIV](), g[TR]() / g[TR_DIV](), g[TD]() / g[TD_DIV]()
        error = float(g[SETPOINT]() - g[SENSOR]())
        filt = g[FILTER]()
        if loop.started and filt:
            error = (error - loop.e1) * filt / 100 + loop.e1
        if abs(error) < g[DEADZONE]():
            error = 0.0
        if b[PID_K_BITS + x] or not loop.started:
            b[PID_K_BITS + x] = 0
            iterm0 = g[ITERM0]()
            loop.iterm = float(iterm0 - 0x10000 if iterm0 & 0x8000 else iterm0)
            loop.e1 = loop.e2 = error
            loop.u1 = float(g[XOUT]())
            loop.last, loop.started = ctx.now, True
        else:
            dt = ctx.now - loop.last
            loop.last = ctx.now
            if dt > 0:
                _compute(formula, loop, kp, tr, td, error, dt, xmin, xmax)
                p[XOUT](int(loop.u1))
            loop.e2, loop.e1 = loop.e1, error
        p[ERROR](_signed16(error))
        p[ABS_ERROR](min(0xFFFF, round(abs(error))))
        p[ITERM](_signed16(loop.iterm))

    def step(ctx: FonContext) -> None:
        for x, g, p, loop in regs:
            if enable >> x & 1:
                run_one(ctx, x, g, p, loop)
            else:
                b[PID_CTRL_BITS + x] = 0

    return step


def _compute(formula: int, loop: _Loop, kp: float, tr: float, td: float, error: float, dt: float,
             xmin: int, xmax: int) -> None:
    """One regulator step: new XOUT in loop.u1 (rounded, clamped), integral updated with anti-windup."""
    dterm = (error - loop.e1) / dt
    old_iterm = loop.iterm
    if formula == 2:
        half = dt / (2 * tr) if tr else 0.0
        q0 = kp * (1 + half + td / dt)
        q1 = -kp * (1 + 2 * td / dt - half)
        q2 = kp * td / dt
        out = loop.u1 + q0 * error + q1 * loop.e1 + q2 * loop.e2
    elif formula in (0, 1):
        loop.iterm += error * dt
        integral = loop.iterm / tr if tr else 0.0
        out = kp * error + (kp * (integral + dterm * td) if formula == 0 else integral + dterm * td)
    else:
        loop.iterm += kp * error * dt / tr if tr else 0.0
        out = kp * error + kp * td * dterm + loop.iterm
    clamped = min(xmax, max(xmin, round(out)))
    if clamped != round(out) and (loop.iterm - old_iterm) * (out - clamped) > 0:
        loop.iterm = old_iterm
    loop.u1 = float(clamped)

