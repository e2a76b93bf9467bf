"""Renderer-neutral scene specs: generate, validate, digest and texture them.

``spec``
    Load, validate (``schemas/scene.schema.yaml``), digest and write scene specs.
``generate``
    The deterministic generator of indoor stereo scenes (scene ``i`` of seed ``s`` depends
    on ``(s, i)`` only), from its parts: ``builder`` (the scene draft, its palette and
    room), ``furniture`` (furniture and glass objects) and ``raycast`` (the ray-cast checks
    of a layout and the lighting model that sets the lights' radiance).
``textures``
    Procedural diffuse textures baked to bitmaps.
``references``
    The files a Mitsuba XML scene reads (meshes, textures, spectra, includes), tracked and
    hashed as the scene's content.

Importing this package imports none of its modules (nor numpy or jsonschema).
"""
