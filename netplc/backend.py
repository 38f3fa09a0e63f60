"""What the engine's two program backends share: the compiled program (netplc/compiler.py) and the
reference interpreter (netplc/interpreter.py) each run one scan on a `ScanHost`.

The engine is the host; it picks a backend and calls it, and neither backend imports the engine
back: they see only this interface (memory, the TIM/CTR value lists, the FON steps and the way a
failing function is reported). So the compiler can be tested on its own and the equivalence tests
hold both backends to the same host.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal, Protocol

from netplc.functions._util import Step
from netplc.functions.registry import Fon, FonContext, FunctionSpec

WATCHDOG_STEPS = 1_000_000  # instructions per scan before the scan is abandoned (endless jump loop)

Outcome = Literal["halt", "watchdog"] | None  # how a scan ended: None at the end of the program
Backend = Callable[[], Outcome]  # one scan of a loaded program


class ScanHost(FonContext, Protocol):
    tim_ticks: list[float]  # TIM current values by coil address C; changed in place only
    ctr_values: list[int]  # CTR current values by coil address C; changed in place only
    fons: dict[int, tuple[Fon, FunctionSpec | None]]  # FON instructions by index, with their function

    def instruction_call(self, index: int) -> Callable[[int], None]:
        """The closure that runs the TIM, CTR or FON at `index` with its chain result RES."""
        ...

    def fon_step(self, index: int) -> Step:
        """The function of the FON at `index`, bound to its operands once."""
        ...

    def fon_failed(self, index: int, e: Exception) -> None:
        """A function raised: FErr1, and one 'system' record per instruction."""
        ...
