"""The protocol fuzzer (``pltf fuzz``): spec-driven generation, mutation of valid traffic, XML attacks and
stateful fuzzing against a PlatformCtrl implementation over TCP, or against ``pltf.spec.codec`` and
``pltf.spec.documents`` in-process. See fuzz/README.md for the design; the modules, in the order a case goes:
``generate``/``mutate``/``xml_attacks`` -> ``schedule`` (with ``safety``) -> ``engine`` (with ``target``,
``flight``, ``knowledge``) -> ``findings`` (with ``minimize``, ``launch``) -> ``report`` (with ``pcapng``).
"""
