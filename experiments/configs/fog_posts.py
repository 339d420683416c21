# The lamp posts of seed 002's S2 and S3 (render/fog/scenes.cpp: AnalyticPost) as OBJ meshes for
# `meltlab render --mesh` (16-sided prisms with caps, as fog_frame.h's scene_mesh tessellates them):
#   python3 fog_posts.py fog_lamp_post.obj "0,0.35,0.08,0,4.2"
#   python3 fog_posts.py fog_street_posts.obj "0,2.4,0.08,0,5.1;10,2.4,0.08,0,5.1;20,2.4,0.08,0,5.1;30,2.4,0.08,0,5.1"
import math, sys
def prisms(posts, sides=16):
    v, f = [], []
    for (x, y, r, z0, z1) in posts:
        b = len(v)
        for z in (z0, z1):
            for k in range(sides):
                a = 2 * math.pi * k / sides
                v.append((x + r * math.cos(a), y + r * math.sin(a), z))
        v.append((x, y, z0)); v.append((x, y, z1))
        c0, c1 = b + 2 * sides, b + 2 * sides + 1
        for k in range(sides):
            k1 = (k + 1) % sides
            f.append((b + k, b + k1, b + sides + k1)); f.append((b + k, b + sides + k1, b + sides + k))
            f.append((c0, b + k1, b + k)); f.append((c1, b + sides + k, b + sides + k1))
    return v, f
name, spec = sys.argv[1], sys.argv[2]
posts = [tuple(map(float, p.split(','))) for p in spec.split(';')]
v, f = prisms(posts)
with open(name, 'w') as o:
    o.write(f"# {len(posts)} lamp post(s) of seed 002's S2/S3 (render/fog/scenes.cpp): x, y, radius, z0, z1 = {spec}\n")
    o.write("# 16-sided prisms with caps, metres, z up; written by experiments/configs/fog_posts.py\n")
    for p in v: o.write("v %.6g %.6g %.6g\n" % p)
    for t in f: o.write("f %d %d %d\n" % tuple(i + 1 for i in t))
