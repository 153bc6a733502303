#!/usr/bin/python3
"""Sprites and scenes for the movers no detector knows (issue 50), made with the shared generator.

usage: make_movers.py sprites OUT_SPRITES          cut the object sprites from the Bonn slice
       make_movers.py scene SRC SPRITES SCENARIO OUT  make_dynamic_sequence.py, plus "stop_at_s"

A walker with "stop_at_s" (seconds from the first frame) moves along its path until then and
stands at that place from then on, facing where the camera was when it stopped; from
"stop_at_s" + "settle_s" (default 0.5) its pixels are labelled 128 (static) in mask/, as a
standing person's are, and their clean geometry goes to reference_settled.ply (1 cm voxels): the
place where it stands, which the map should hold (the generator's reference_static.ply is the
room without it, and its reference_dynamic.ply holds the place too, from the frames before it
settled). Everything else is ../shared/tools/dyndata/make_dynamic_sequence.py.
"""
import os, subprocess, sys
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.path.normpath(os.path.join(HERE, '../../../shared/tools/dyndata'))
BONN_FRAME = '../data/bonn/rgbd_bonn_crowd_400_499/rgb/1548339833.28164.jpg'
SPRITES = {   # name: polygon in BONN_FRAME
    'chair': '158,198 222,196 233,214 231,300 226,330 212,345 240,372 214,385 190,370 178,385 150,383 128,387 '
             '125,352 148,343 150,322 121,282 119,266 145,266 148,215',
    'scope_box': '405,195 462,195 462,226 405,226',
    'table_cart': '407,195 460,195 462,225 520,230 520,262 384,262 384,378 376,378 374,250 378,228 405,225',
}


def make_sprites(out):
    frame = os.path.normpath(os.path.join(TOOLS, '..', BONN_FRAME))
    for name, poly in SPRITES.items():
        subprocess.run([sys.executable, f'{TOOLS}/make_object_sprite.py', frame, out, name, f'photo:bonn_{name}', poly],
                       check=True)


def add_stops(g):
    """Patch the generator's walkers: a walker with stop_at_s stands still from then on."""
    geometry = g.Walker.geometry

    def stopping_geometry(self, sc, t, cam):
        t_stop = self.spec.get('stop_at_s')
        if t_stop is None:
            return geometry(self, sc, t, cam)
        t = np.asarray(t, float)
        after = t > t_stop
        cam_stop = sc.cams[min(int(np.searchsorted(sc.t, t_stop)), sc.N - 1)]
        if t.ndim == 0:
            settled = t > t_stop + self.spec.get('settle_s', 0.5)
            self.label = g.STATIC if settled else g.MOVING
        cam = np.where(after[..., None], cam_stop, cam)
        return geometry(self, sc, np.minimum(t, t_stop), cam)

    g.Walker.geometry = stopping_geometry


def gather_settled(g):
    """Patch the generator's render: the colour frames' pixels labelled static (settled movers)
    go, as clean geometry, into the returned accumulator."""
    render, settled = g.render, g.VoxelAccumulator(0.01)

    def render_gathering(sc, walkers, t, T, d_src, rgb=None):
        out = render(sc, walkers, t, T, d_src, rgb)
        if rgb is not None:
            _, mask, zper = out
            settled.add(g.backproject(np.where(mask == g.STATIC, zper, 0), T))
        return out

    g.render = render_gathering
    return settled


def make_scene(args):
    sys.path.insert(0, TOOLS)
    import make_dynamic_sequence as g
    add_stops(g)
    settled = gather_settled(g)
    sys.argv = ['make_dynamic_sequence.py'] + args
    g.main()
    points = settled.result()
    if len(points):
        g.write_ply(os.path.join(args[-1], 'reference_settled.ply'), points)


if __name__ == '__main__':
    if len(sys.argv) == 3 and sys.argv[1] == 'sprites':
        make_sprites(sys.argv[2])
    elif len(sys.argv) == 6 and sys.argv[1] == 'scene':
        make_scene(sys.argv[2:])
    else:
        sys.exit(__doc__)
