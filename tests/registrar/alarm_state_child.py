"""Child process of the alarm-state crash test: saves 200 alarm states without end, each round in
one transaction, and prints each round once it is saved. The parent kills it with SIGKILL."""

import sys

from registrar.alarm_state import AlarmStateFile


def main(path: str) -> None:
    states = AlarmStateFile(path)
    n = 0
    while True:
        n += 1
        states.update({f"A{i:03d}": {"round": n, "acked": n % 2 == 0} for i in range(200)})
        print(n, flush=True)  # update() without a writer thread saves before it returns


if __name__ == "__main__":
    main(sys.argv[1])
