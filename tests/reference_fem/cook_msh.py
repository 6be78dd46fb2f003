# Cook's membrane as a structured (bilinear-mapped) triangle mesh in .msh 2.2: the trapezoid
# (0,0) (48,44) (48,60) (0,44), groups "clamp" (x = 0) and "load" (x = 48).
import sys
n = int(sys.argv[2])
corner = [(0, 0), (48, 44), (48, 60), (0, 44)]
def at(i, j):
    s, t = i / n, j / n
    x = (1 - s) * ((1 - t) * corner[0][0] + t * corner[3][0]) + s * ((1 - t) * corner[1][0] + t * corner[2][0])
    y = (1 - s) * ((1 - t) * corner[0][1] + t * corner[3][1]) + s * ((1 - t) * corner[1][1] + t * corner[2][1])
    return x, y
node = lambda i, j: 1 + i * (n + 1) + j
lines, tris = [], []
for j in range(n):
    lines.append((2, node(0, j), node(0, j + 1)))
    lines.append((3, node(n, j), node(n, j + 1)))
for i in range(n):
    for j in range(n):
        a, b, c, d = node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)
        tris += [(a, b, c), (a, c, d)] if (i + j) % 2 == 0 else [(a, b, d), (b, c, d)]
with open(sys.argv[1], "w") as f:
    f.write('$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n1 2 "clamp"\n1 3 "load"\n2 1 "domain"\n$EndPhysicalNames\n')
    f.write(f"$Nodes\n{(n + 1) ** 2}\n")
    for i in range(n + 1):
        for j in range(n + 1):
            x, y = at(i, j)
            f.write(f"{node(i, j)} {x!r} {y!r} 0\n")
    f.write(f"$EndNodes\n$Elements\n{len(lines) + len(tris)}\n")
    k = 1
    for tag, a, b in lines:
        f.write(f"{k} 1 2 {tag} {tag} {a} {b}\n"); k += 1
    for a, b, c in tris:
        f.write(f"{k} 2 2 1 1 {a} {b} {c}\n"); k += 1
    f.write("$EndElements\n")
