"""Draws docs/images/pitch-geometry.svg, the derived channels of the pitch world:

    python docs/images/pitch_geometry.py docs/images/pitch-geometry.svg   (needs matplotlib)
"""
import math, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import Arc, FancyArrowPatch, Rectangle
plt.rcParams["svg.fonttype"] = "none"
fig, ax = plt.subplots(figsize=(10, 6.9))
ax.add_patch(Rectangle((-2100, -1350), 4200, 2700, facecolor="#e8f4e4", edgecolor="#5a8f4e", lw=2))
ax.plot([0, 0], [-1350, 1350], color="#5a8f4e", lw=1)
for side in (-1, 1):
    ax.plot([side * 2100] * 2, [-400, 400], color="#c33", lw=6, solid_capstyle="butt")
O, G, B, R, heading = (-2100, 0), (2100, 0), (400, 600), (-800, -350), 35.0
def arrow(a, b, color, lw=2, style="-|>", ls="-"):
    ax.add_patch(FancyArrowPatch(a, b, arrowstyle=style, mutation_scale=14, color=color, lw=lw, linestyle=ls))
def deg(a, b): return math.degrees(math.atan2(b[1] - a[1], b[0] - a[0]))
ax.plot(*O, "o", color="#c33", ms=8); ax.plot(*G, "o", color="#c33", ms=8)
ax.text(-2050, -120, "own_goal (−length/2, 0)", fontsize=10, va="top")
ax.text(2050, -120, "goal (+length/2, 0)", fontsize=10, va="top", ha="right")
# the line ball -> own goal, R's offset from it
ax.plot([B[0], O[0]], [B[1], O[1]], color="#8e44ad", lw=1.5, ls="--")
dx, dy = O[0] - B[0], O[1] - B[1]; L = math.hypot(dx, dy); ux, uy = dx / L, dy / L
t = (R[0] - B[0]) * ux + (R[1] - B[1]) * uy; foot = (B[0] + t * ux, B[1] + t * uy)
arrow(foot, R, "#8e44ad", style="<|-|>")
ax.text(-2000, -650, "offset [ball, own_goal, robot]: the signed distance of R from the line\nball → own_goal (positive when R lies to its left; here positive)", fontsize=10, color="#8e44ad", va="top")
# angle at R between ball and own goal
aB, aO = deg(R, B), deg(R, O)
ax.plot([R[0], R[0] + 0.3 * (O[0] - R[0])], [R[1], R[1] + 0.3 * (O[1] - R[1])], color="#16a085", lw=1.5)
ax.add_patch(Arc(R, 420, 420, theta1=aB, theta2=aO if aO > aB else aO + 360, color="#16a085", lw=2))
ax.text(-2000, -980, "angle [ball, robot, own_goal]: the angle at R between R → ball and\nR → own_goal; 180 when R stands between them (a defender's place)", fontsize=10, color="#16a085", va="top")
# distance
ax.plot([R[0], B[0]], [R[1], B[1]], color="#555", lw=1.5, ls=":")
ax.text((R[0] + B[0]) / 2 + 60, (R[1] + B[1]) / 2 - 60, "distance [ball, robot]", fontsize=10, color="#555", ha="left", va="top", rotation=deg(R, B), rotation_mode="anchor")
# robot and heading
ax.plot(*R, "o", color="#2c6fbb", ms=14); ax.text(R[0] - 80, R[1] - 110, "robot R", ha="right", fontsize=11)
h = (R[0] + 450 * math.cos(math.radians(heading)), R[1] + 450 * math.sin(math.radians(heading)))
arrow(R, h, "#2c6fbb", lw=2.5); ax.text(h[0] + 10, h[1] - 120, "heading", color="#2c6fbb", fontsize=10)
# ball, bearing [ball, goal]
ax.plot(*B, "o", color="#f39c12", ms=10); ax.text(B[0] + 60, B[1] + 60, "ball", fontsize=11)
gdir = deg(B, G)
arrow(B, (B[0] + 1100 * math.cos(math.radians(gdir)), B[1] + 1100 * math.sin(math.radians(gdir))), "#c0392b")
hb = (B[0] + 650 * math.cos(math.radians(heading)), B[1] + 650 * math.sin(math.radians(heading)))
ax.plot([B[0], hb[0]], [B[1], hb[1]], color="#2c6fbb", lw=1.5, ls="--")
ax.add_patch(Arc(B, 800, 800, theta1=gdir, theta2=heading, color="#c0392b", lw=2))
ax.text(700, 1250, "bearing [ball, goal]: the direction ball → goal\nrelative to the robot's heading (dashed copy);\nhere negative (to the right); 0 when R faces along it", fontsize=10, color="#c0392b", va="top")
# velocity
arrow(B, (B[0] - 300, B[1] + 250), "#b9770e", lw=2.5)
ax.text(B[0] - 350, B[1] + 650, "velocity [ball, x | y | speed]:\nthe last step's displacement", fontsize=10, color="#b9770e", ha="center", va="top")
ax.annotate("", xy=(2250, -1500), xytext=(-2250, -1500), arrowprops=dict(arrowstyle="-|>", color="#333"))
ax.text(2250, -1560, "x (towards the target goal)", ha="right", va="top", fontsize=10)
ax.annotate("", xy=(-2250, 1500), xytext=(-2250, -1500), arrowprops=dict(arrowstyle="-|>", color="#333"))
ax.text(-2200, 1480, "y", fontsize=10, va="top")
ax.set_xlim(-2350, 2350); ax.set_ylim(-1800, 1600); ax.set_aspect("equal"); ax.axis("off")
ax.set_title("Derived channels of the pitch world (mm, deg; angles counter-clockwise = to the left)\nBearings are relative to the robot's heading; distance, offset, angle and velocity are not", fontsize=11)
fig.tight_layout()
fig.savefig(sys.argv[1], metadata={"Date": None} if sys.argv[1].endswith(".svg") else None)
