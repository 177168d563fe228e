"""Reference for tests/delays.rs: PathSim's anti-windup PID example with a
2 s transport delay in the loop, solved by the method of steps.

    r(t)  = 0, 10 from t = 10, 5 from t = 100      (setpoint)
    e     = r − y(t − 2)                           (y = 0 before t = 2)
    v     = kp·e + I + kd·N·(e − x_f)               (the PID's unlimited output)
    I'    = ki·e + kb·(sat20(v) − v)                (back-calculation, kb = Ki·Ks)
    x_f'  = N·(e − x_f)
    a     = sat10(v)                                (the actuator)
    y'    = 0.1·(a − y)                             (plant 0.1/(s + 0.1))

kp 1.5, ki 0.5, kd 0.2, N 10, Ks 10 (so kb = 5), limits ±20, actuator ±10.
The delay differential equation is integrated interval by interval between
breakpoints (t = 0, the setpoint steps, every saturation switch, and each of
these shifted by multiples of the delay), each interval with SciPy's DOP853
at rtol 1e-13 and the saturations' modes fixed, switching located as
events; y(t − 2) comes from the earlier intervals' dense output.
Writes t, a(t) and y(t) on a 0.25 s grid to tests/data/antiwindup_delay.csv.

    python3 -m venv venv && venv/bin/pip install scipy && venv/bin/python tests/reference/antiwindup_delay.py
"""
import bisect
import os

import numpy as np
from scipy.integrate import solve_ivp

KP, KI, KD, N, KB = 1.5, 0.5, 0.2, 10.0, 0.5 * 10.0
TAU, STOP = 2.0, 200.0
RTOL, ATOL = 1e-13, 1e-15

pieces = []  # (t0, t1, dense output of [I, x_f, y])
starts = []  # their t0, for bisection


def y_past(t):
    if t < 0.0 or not pieces:
        return 0.0
    k = max(bisect.bisect_right(starts, t) - 1, 0)
    t0, t1, sol = pieces[k]
    return sol(min(max(t, t0), t1))[2]


def r(t, side):
    # side: +1 right limit at a breakpoint, −1 left limit
    def at(tt):
        return 10.0 if 10.0 <= tt < 100.0 else (5.0 if tt >= 100.0 else 0.0)
    return at(t if side > 0 else np.nextafter(t, -np.inf))


def unlimited(t, z, r_now):
    e = r_now - y_past(t - TAU)
    return KP * e + z[0] + KD * N * (e - z[1]), e


def rhs_for(m20, m10, r_now):
    def f(t, z):
        v, e = unlimited(t, z, r_now)
        u = v if m20 == 0 else 20.0 * m20
        a = v if m10 == 0 else 10.0 * m10
        return [KI * e + KB * (u - v), N * (e - z[1]), 0.1 * (a - z[2])]
    return f


def mode(v, limit):
    return 1 if v > limit else (-1 if v < -limit else 0)


def events_for(m20, m10, r_now):
    """The switching functions the modes watch, with (limit, direction) of each."""
    evs, what = [], []
    for limit, m in ((20.0, m20), (10.0, m10)):
        for sign in ((1, -1) if m == 0 else (m,)):
            def g(t, z, limit=limit, sign=sign):
                return unlimited(t, z, r_now)[0] - sign * limit
            g.terminal = True
            g.direction = sign if m == 0 else -m  # into the limit, or out of it
            evs.append(g)
            what.append((limit, sign))
    return evs, what


breakpoints = sorted({k * TAU for k in range(int(STOP / TAU) + 1)} | {10.0 + k * TAU for k in range(96)}
                     | {100.0 + k * TAU for k in range(51)})
breakpoints = [b for b in breakpoints if b <= STOP]
t, z = 0.0, np.zeros(3)
m20 = m10 = 0
switched = False
while t < STOP - 1e-12:
    nxt = next(b for b in breakpoints if b > t + 1e-12)
    r_now = r(t, 1)  # the setpoint holds between breakpoints
    if not switched:  # away from a switch, v is off the limits: its modes are plain
        v, _ = unlimited(t, z, r_now)
        m20, m10 = mode(v, 20.0), mode(v, 10.0)
    evs, what = events_for(m20, m10, r_now)
    sol = solve_ivp(rhs_for(m20, m10, r_now), (t, nxt), z, method="DOP853", rtol=RTOL, atol=ATOL,
                    dense_output=True, events=evs)
    t_end = sol.t[-1]
    pieces.append((t, t_end, sol.sol))
    starts.append(t)
    switched = sol.status == 1
    if switched:  # a saturation switched: a breakpoint, propagated by the delay
        fired = next(k for k, te in enumerate(sol.t_events) if len(te))
        limit, sign = what[fired]
        if limit == 20.0:
            m20 = sign if m20 == 0 else 0
        else:
            m10 = sign if m10 == 0 else 0
        for k in range(1, int((STOP - t_end) / TAU) + 1):
            bisect.insort(breakpoints, t_end + k * TAU)
    t, z = t_end, sol.y[:, -1]
    if os.environ.get("TRACE"):
        print(f"{t:.9f} m20={m20} m10={m10} status={sol.status} nfev={sol.nfev}", flush=True)

grid = np.arange(0, int(STOP / 0.25) + 1) * 0.25
out = os.path.join(os.path.dirname(__file__), "..", "data", "antiwindup_delay.csv")
os.makedirs(os.path.dirname(out), exist_ok=True)
with open(out, "w") as f:
    f.write("t,a,y\n")
    for tg in grid:
        k = max(bisect.bisect_right(starts, tg) - 1, 0)
        t0, t1, s = pieces[k]
        zz = s(min(max(tg, t0), t1))
        v = KP * (r(tg, 1) - y_past(tg - TAU)) + zz[0] + KD * N * ((r(tg, 1) - y_past(tg - TAU)) - zz[1])
        f.write(f"{float(tg)!r},{float(min(max(v, -10.0), 10.0))!r},{float(zz[2])!r}\n")
print("pieces", len(pieces), "written", out)
