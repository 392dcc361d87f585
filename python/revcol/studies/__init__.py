"""Studies built on the library: what the paper and the issues measured with it, each with its
own command line (``python -m revcol.studies.<name>``, or ``revcol study`` / ``revcol bench``).

- :mod:`.equilibrium`: does a collision law keep a hard-sphere gas in equilibrium
  (``revcol study equilibrium``), with :mod:`.eos` (equations of state) and :mod:`.ecmc`
  (event-chain Monte Carlo, the same N without dynamics); :mod:`.eos_replicas` (independent
  replicas of one point, Z(N) fits) and :mod:`.eos_zinf_compare` (the engine's Z(inf) against
  the chains'); :mod:`.maxwell` (relaxation to Maxwell-Boltzmann speeds) and :mod:`.transport`
  (self-diffusion against Enskog);
- :mod:`.stability`: the numerical stress suite (``revcol study stability``);
- :mod:`.randomness`: the paper's dieharder experiment and coverage figures (``revcol study
  randomness``), reading :mod:`.words`; :mod:`.randomness_increments` (KS of a stream's increments);
- :mod:`.verify_all`: ``revcol.verify`` on every named exact case, and the cells' bits K against
  precision and memory; :mod:`.lattice3d_candidates`: the 3D lattice direction chart's
  cube-sphere candidate, measured geometrically;
- :mod:`.statesave`: the paper's state saving vs reverse computation (``revcol bench statesave``);
- :mod:`.tradeoff`: run time against error for every operator and knob (``revcol bench tradeoff``);
- :mod:`.paper_study`: how often the paper's printed procedures fail, their bias and uniformity;
- :mod:`.horizon`, :mod:`.paper_scenes` and :mod:`.scenes`: what ``revcol run`` does with a scene
  (the horizon, the reversal and statesave scene kinds, and :func:`.scenes.run_scene`).

The library (every ``revcol`` module outside ``studies``, ``sweep`` and ``cli``) never imports
from here: the studies import the library, and ``revcol.sweep`` and ``revcol.cli`` run them
(``tests/python/test_imports.py`` checks it).
"""
