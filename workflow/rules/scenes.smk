# Deterministic scene generator: writes scenes/scene_NNN.yaml when a listed spec is missing.
# The committed specs are its output for generator.seed = 0; existing specs are left alone
# (regenerate them all with `stereovar scenes generate --count 20 --seed 0 --out scenes`).


rule generate_scene:
    output:
        "scenes/{scene}.yaml",
    wildcard_constraints:
        scene=GENERATE_PATTERN,
    params:
        seed=config["generator"]["seed"],
    log:
        "logs/scenes/{scene}.log",
    benchmark:
        "benchmarks/scenes/{scene}.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/generate_scene.py"
