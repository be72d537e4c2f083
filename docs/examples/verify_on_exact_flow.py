"""Each window edge of the two example reports, checked by closed-form shooting on the exact flow:
the orbit (period M, k contacts) is marched from inside the window on mapcheck.exact's flow, Newton
at every step; it must be stable just inside the edge and be gone (not converged, unstable, other
contacts, or a shorter period) just outside."""
import json, sys
import numpy as np
ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
from mapcheck.exact_flow import ExactFlow

def minimal(z, rtol=1e-6):
    M = len(z)
    for d in range(1, M):
        if M % d == 0 and np.max(np.abs(np.roll(z, -d, axis=0) - z)) <= rtol * max(1e-12, np.max(np.abs(z))):
            return d
    return M

def settle(flow, s, M, k, starts, n=600):
    step = flow.step_of(s)
    for z0 in starts:
        z = np.array(z0, float)
        try:
            for _ in range(n):
                *z, c = step(*z)
        except Exception:
            continue
        o = flow.orbit(s, M, z)
        if o.converged and o.stable and int(np.sum(o.contacts)) == k and minimal(o.z) == M:
            return o
    return None

def march(flow, M, k, orb, s0, s1, steps=60):
    """Continue from s0 to s1; return (last good sigma, orbit) and whether s1 was reached."""
    z, s = orb.z[0], s0
    for sk in np.linspace(s0, s1, steps + 1)[1:]:
        o = flow.orbit(sk, M, z)
        ok = o.converged and o.stable and int(np.sum(o.contacts)) == k and minimal(o.z) == M
        if not ok:
            return s, False
        z, s = o.z[0], sk
    return s, True

def march2(flow, M, k, orb, s0, s1, steps):
    z, s, o_last = orb.z[0], s0, orb
    for sk in np.linspace(s0, s1, steps + 1)[1:]:
        o = flow.orbit(sk, M, z)
        if not (o.converged and o.stable and int(np.sum(o.contacts)) == k and minimal(o.z) == M):
            return s, False, o_last
        z, s, o_last = o.z[0], sk, o
    return s, True, o_last

starts = [(u, v) for u in np.linspace(-4, -0.2, 7) for v in np.linspace(-12, 12, 7)]
for name, flow in (("rigid", ExactFlow(0.8, 2.5, 0.95, 10.0, "rigid")),
                   ("underdamped", ExactFlow(0.3, 1.2, 0.8, 10.0, "compliant"))):
    res = json.load(open(ROOT / "docs" / "examples" / f"windows-{name}" / "windows.json"))
    for r in res["ode_windows_all"]:
        if not r["resolved"]:
            continue
        M, k, lo, hi = r["M"], r["impacts"], r["lo"], r["hi"]
        a = lo if lo is not None else -0.3
        b = hi if hi is not None else 0.3
        mid = 0.5 * (a + b)
        if k == 0:
            o = flow.orbit(mid, 1, [(1 + mid) * np.cos(np.pi) - 1, 0.0])
        else:
            o = settle(flow, mid, M, k, starts)
        if o is None:
            print(f"{name} {M}/{k}: no such attractor at the window's middle {mid:.5f} on the exact flow"); continue
        out = []
        for edge, end in ((lo, -0.3), (hi, 0.3)):
            if edge is None:
                s, reached = march(flow, M, k, o, mid, end)
                out.append(f"open: reaches {end:+.2f} {'yes' if reached else 'NO, lost at %.6f' % s}")
                continue
            h = max(2e-4 * abs(edge), 2e-5)
            d = np.sign(edge - mid)
            s_in, r_in, o_in = march2(flow, M, k, o, mid, edge - d * h, 200)
            # one Newton step across the edge from the orbit just inside it
            oo = flow.orbit(edge + d * h, M, o_in.z[0]) if r_in else None
            there = bool(oo is not None and oo.converged and oo.stable and int(np.sum(oo.contacts)) == k and minimal(oo.z) == M)
            why = "" if oo is None else (" (Newton: not converged)" if not oo.converged else
                  f" (max|mu| {np.abs(oo.multipliers).max():.4f}, contacts {int(np.sum(oo.contacts))}, period {minimal(oo.z)})")
            out.append(f"edge {edge:+.6f}: stable at edge{-d * h:+.0e} {'yes' if r_in else 'NO (lost at %.6f)' % s_in}, "
                       f"at edge{d * h:+.0e} {'STILL THERE' if there else 'gone'}{why}")
        print(f"{name} {M}/{k} [{lo}, {hi}]: " + "; ".join(out))
