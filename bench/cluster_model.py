#!/usr/bin/env python3
"""The scaling model of docs/cluster.md ("A model for a cluster"), from measured constants.

One case split over P ranks of one core each. Per rank and step:
  work           W = (N / P) t_p
  communication  C = m alpha + G b / beta + 2 alpha log2(P) + G t_g
with G the ghosts a rank receives, m its messages (2 for slabs; 26 for boxes cut along three
axes: 13 neighbours, forward and back), b the bytes a ghost costs, alpha the latency, beta the
bandwidth; the efficiency is W / (W + C). The particles are beads of diameter d packed at a solid
fraction phi in a box of 10 : 5 : 1, ghosts within a reach of 1.25 d: a slab cut across the
longest side receives one whole cross section, a cube the layers on three of its faces.

t_p and t_g come from benchmark B3 (bench/b3_decomposition.sh): t_p the time per particle-step of
one rank of one thread in the dense bed, t_g rank 0's communication time per step divided by its
ghosts (waiting for the neighbour included). alpha and beta are those of the cluster's network.

Usage: python3 bench/cluster_model.py --tp-ns 150 --ghost-ns 110 [--alpha-us 2] [--beta-gbs 10]
       [--ghost-bytes 120] [--d 0.004] [--phi 0.6]
Prints the table in Markdown.
"""
import argparse
import math


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tp-ns", type=float, required=True, help="time per particle-step on one core [ns]")
    parser.add_argument("--ghost-ns", type=float, required=True, help="communication time per ghost and step [ns]")
    parser.add_argument("--alpha-us", type=float, default=2.0, help="message latency [us]")
    parser.add_argument("--beta-gbs", type=float, default=10.0, help="bandwidth [GB/s]")
    parser.add_argument("--ghost-bytes", type=float, default=120.0, help="bytes sent per ghost and step")
    parser.add_argument("--d", type=float, default=0.004, help="bead diameter [m]")
    parser.add_argument("--phi", type=float, default=0.6, help="solid fraction")
    a = parser.parse_args()

    alpha, beta = a.alpha_us * 1e-6, a.beta_gbs * 1e9
    reach = 1.25 * a.d
    per_particle = math.pi / 6 * a.d ** 3 / a.phi  # [m^3] of bed per bead

    def communication(ghosts, messages, ranks):
        return messages * alpha + ghosts * a.ghost_bytes / beta + 2 * alpha * math.log2(ranks) + ghosts * a.ghost_ns * 1e-9

    print(f"t_p = {a.tp_ns:g} ns, t_g = {a.ghost_ns:g} ns, alpha = {a.alpha_us:g} us, beta = {a.beta_gbs:g} GB/s, "
          f"{a.ghost_bytes:g} B a ghost; beads of {1000 * a.d:g} mm at {a.phi:g}, reach 1.25 d, a box 10 : 5 : 1\n")
    print("| N | P | particles per rank | W | slabs: ghosts, efficiency | cubes: ghosts, efficiency |")
    print("|---|---|---|---|---|---|")
    for n in (1e6, 1e7):
        volume = n * per_particle
        length = (20 * volume) ** (1 / 3)  # the box is length x length/2 x length/10
        for ranks in (64, 256, 1024):
            work = n / ranks * a.tp_ns * 1e-9
            slab_ghosts = (length / 2) * (length / 10) * reach / per_particle
            most_slabs = int(length / reach)
            if ranks <= most_slabs:
                e = work / (work + communication(slab_ghosts, 2, ranks))
                slabs = f"{slab_ghosts:,.0f}, {e:.2f}"
            else:
                slabs = f"not possible (at most {most_slabs} slabs in {length:.2f} m)"
            side = (volume / ranks) ** (1 / 3)
            cube_ghosts = 3 * side * side * reach / per_particle
            e = work / (work + communication(cube_ghosts, 26, ranks))
            print(f"| 1e{round(math.log10(n))} | {ranks} | {n / ranks:,.0f} | {1e3 * work:.3g} ms | {slabs} | {cube_ghosts:,.0f}, {e:.2f} |")


if __name__ == "__main__":
    main()
