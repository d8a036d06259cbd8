"""Tutorial step 1 (a box of 300 settling grains) built and run from Python.

    python docs/tutorial/settling_box.py

The scenario is the same as docs/tutorial/01_settling_box.toml, written as
Python dicts; the results are the same as `efgdem run` gives for that file.
"""

import numpy as np

import efgdem


def wall(name, start, end):
    return {"name": name, "from": start, "to": end}


scenario = {
    "simulation": {"end_time": 1.0, "gravity": [0.0, -9.81]},
    "material": [
        {"name": "sand", "density": 2650.0, "kn": 1.0e6, "ks": 5.0e5, "friction": 0.5}
    ],
    "granular": {
        "material": "sand",
        "discs": {
            "generate": "random",
            "box": [[0.0, 0.0], [0.3, 0.3]],
            "radius": [0.004, 0.006],
            "count": 300,
            "seed": 1,
        },
        "damping": {"kind": "critical-ratio", "zeta": 0.2},
    },
    "wall": [
        wall("floor", [0.0, 0.0], [0.3, 0.0]),
        wall("left", [0.0, 0.0], [0.0, 0.4]),
        wall("right", [0.3, 0.0], [0.3, 0.4]),
    ],
    "probe": [{"name": "floor_fy", "wall": "floor", "quantity": "wall_fy"}],
}

model = efgdem.Model.from_dict(scenario)
print(f"{model.n_discs} discs, dt = {model.dt:.3e} s, {model.steps} steps")

# step in chunks of 0.1 s and watch the grains come to rest
while model.step_count < model.steps:
    model.run(min(model.time + 0.1, model.end_time))
    speed = np.linalg.norm(model.disc_velocities(), axis=1)
    print(f"t = {model.time:.2f} s  fastest grain {speed.max():.2e} m/s")

contacts = model.contacts()
y = model.disc_positions()[:, 1] + model.disc_radii()
print(f"contacts: {len(contacts)}")
print(f"floor force: {model.probe('floor_fy'):.1f} N")
print(f"highest grain top: {y.max():.3f} m")
