"""The physics check: the task in MuJoCo, replayed and in closed loop (docs/physics.md).

* :mod:`.settings`: the ``physics:`` section of an experiment file (servo gains,
  thresholds, the default object), validated.
* :mod:`.mjcf`: an MJCF model built from the task: the arms from their Pinocchio
  models, the object as a free body, the grasps as a weld and frictionless slides.
* :mod:`.plant`: the model as a plant the rollout drives (``dualarm-qp run --plant
  mujoco``), with joint servos at 1 ms substeps, and what it measures.
* :mod:`.check`: ``dualarm-qp physics RUN_DIR``: the rigid replay of a recorded run, the
  closed loop, and the verdict.

MuJoCo is imported only by the functions that run it: ``import dualarm_qp`` works
without it (``pip install "dualarm-qp[physics]"`` brings it).
"""
