"""Five units of a small designed strip (arched, a spacer, a flipped one with its own b), for
the drawing, sheet and workshop tests."""

from snapmorph.design import Unit

T, W = 0.5e-3, 5e-3
FIVE = [Unit(L=0.0726, h=0.0069, t=T, w=W, side=1),
        Unit(L=0.0738, h=0.0113, t=T, w=W, side=1),
        Unit(L=0.0673, h=0.0, t=T, w=W, side=0),
        Unit(L=0.1294, h=0.0211, t=T, w=W, side=1),
        Unit(L=0.1332, h=0.0313, t=T, w=W, side=-1, b=2e-3)]
