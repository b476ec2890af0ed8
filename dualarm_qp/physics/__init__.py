"""The physics check: the task in MuJoCo, replayed and in closed loop (docs/physics.md).

* :mod:`.settings`: the ``physics:`` section of an experiment file in SI units (servo
  gains, thresholds, the default object); the file's schema is
  :mod:`dualarm_qp.experiments.config_physics`.
* :mod:`.mjcf`: an MJCF model built from the task: the arms from their Pinocchio
  models, the object as a free body, the grasps as a weld and frictionless slides.
* :mod:`.gains`: each joint servo's gains from the arm's own inertia.
* :mod:`.plant`: the model as a plant the rollout drives (``dualarm-qp run --plant
  mujoco``), with joint servos at 1 ms substeps, and what it measures.
* :mod:`.measure`: each hand's wrench on the object and the internal (squeeze) part.
* :mod:`.check`: the rigid replay of a recorded run, the closed loop, and the verdict.
* :mod:`.report`: ``physics.png`` and the physics section of ``report.html``.
* :mod:`.command`: ``dualarm-qp physics RUN_DIR``, which adds them to a run's folder.

MuJoCo is imported only by the functions that run it: ``import dualarm_qp`` works
without it (``pip install "dualarm-qp[physics]"`` brings it).
"""
