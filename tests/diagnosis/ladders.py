"""An RLC ladder of any length: the chain the structural search must stay bounded on."""

from bondgraph import BondGraph


def rlc_ladder(sections: int, sensors: tuple = ("i_1", "v_mid", "v_end")) -> BondGraph:
    """A voltage source feeding ``sections`` sections, each a series R and L then a shunt C to ground.

    Sensors: ``i_<k>`` the current of section k (a Df on its 1-junction), ``v_<k>`` the voltage of its
    capacitor (a De on its 0-junction), ``v_mid`` and ``v_end`` those of the middle and last sections.
    """
    bg = BondGraph(name=f"RLC ladder x{sections}")
    bg.add("u", "Se")
    previous = "u"
    middle = (sections + 1) // 2
    for k in range(1, sections + 1):
        series, node = f"s{k}", f"n{k}"
        bg.add(series, "1")
        bg.add(f"R{k}", "R", value=0.5 + 0.1 * k, uncertainty=(-0.05, 0.05))
        bg.add(f"L{k}", "I", value=1e-3 * (1 + 0.2 * k), uncertainty=(-0.05, 0.05))
        bg.add(node, "0")
        bg.add(f"C{k}", "C", value=1e-4 * (1 + 0.1 * k), uncertainty=(-0.05, 0.05))
        bg.bond(previous, series)
        bg.bond(series, f"R{k}")
        bg.bond(series, f"L{k}")
        bg.bond(series, node)
        bg.bond(node, f"C{k}")
        previous = node
    wanted = {"v_mid": f"n{middle}", "v_end": f"n{sections}"}
    for signal in sensors:
        kind, _, k = signal.partition("_")
        bg.add(signal, "Df" if kind == "i" else "De")
        bg.bond(wanted.get(signal, f"{'s' if kind == 'i' else 'n'}{k}"), signal)
    return bg
