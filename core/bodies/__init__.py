"""Many bodies: certified contacts among N ellipses or ellipsoids (open space or a periodic box).

* :mod:`.build`: the matrices of N shapes from centres, semi-axes and orientations.
* :mod:`.bounds`: certified bounding spheres read off the matrices (and which bodies are valid).
* :mod:`.broadphase`: candidate pairs from a uniform grid per size class (conservative).
* :mod:`.periodic`: the box, minimum images, and pairs whose second body is a lattice image.
* :mod:`.ghosts`: the broad phase in a tilted box (ghost images, then the open-space grid).
* :mod:`.index`: :class:`BodyIndex`, an index asked about new bodies (Monte Carlo, packing).
* :mod:`.narrowphase`: the certified :func:`core.classify` on the candidates, in chunks.
* :mod:`.result`: :class:`Contacts`, what a search returns.
* :mod:`.swept`, :mod:`.sweep`, :mod:`.sweep_result`: moving bodies over one step t in [0, 1]:
  the swept broad phase, ``sweep_contacts()`` and :class:`SweepContacts` (first contact times).
* :mod:`.search`: the search on one machine; :mod:`.distributed`: the same on a Dask cluster;
  :mod:`.contacts`: ``contacts()``, the entry point that picks one.
"""
