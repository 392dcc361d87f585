#!/usr/bin/env python3
"""Prints the constants of cpp/include/revcol/trig.hpp as hex floats, each the double nearest
to its exact value (computed at 50 digits with mpmath; needs `pip install mpmath`, which
revcol itself does not use):

- kSin[k] = (-1)^k (2 pi)^(2k+1) / (2k+1)!,  kCos[k] = (-1)^k (2 pi)^(2k) / (2k)!,  k = 0..8;
- kAtanTurns[i] = atan(i / 32) / (2 pi),  i = 0..32;
- kAtanPoly[k] = (-1)^k / ((2k+1) 2 pi),  k = 0..3.

It also prints the first term each polynomial leaves out at the end of its range (|r| = 1/8
turn, |d| = 1/64), the truncation error the header quotes.

    python3 scripts/trig_coefficients.py
"""
import mpmath as mp

mp.mp.dps = 50
TWO_PI = 2 * mp.pi


def hexes(values):
    return ", ".join(float(v).hex() for v in values)


def main():
    sin = [(-1) ** k * TWO_PI ** (2 * k + 1) / mp.factorial(2 * k + 1) for k in range(9)]
    cos = [(-1) ** k * TWO_PI ** (2 * k) / mp.factorial(2 * k) for k in range(9)]
    atan_turns = [mp.atan(mp.mpf(i) / 32) / TWO_PI for i in range(33)]
    atan_poly = [mp.mpf(-1) ** k / ((2 * k + 1) * TWO_PI) for k in range(4)]
    print("kSin =", hexes(sin))
    print("kCos =", hexes(cos))
    print("kAtanTurns =", hexes(atan_turns))
    print("kAtanPoly =", hexes(atan_poly))
    r, d = mp.mpf(1) / 8, mp.mpf(1) / 64
    print("left out: sin", mp.nstr(TWO_PI ** 19 / mp.factorial(19) * r ** 19, 3),
          "cos", mp.nstr(TWO_PI ** 18 / mp.factorial(18) * r ** 18, 3),
          "atan", mp.nstr(d ** 9 / (9 * TWO_PI), 3))


if __name__ == "__main__":
    main()
