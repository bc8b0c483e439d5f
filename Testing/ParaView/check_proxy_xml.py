# The plugin's server-manager XML against the classes it drives (label paraview): every proxy and
# every property is documented; every number a user sets has a range (or is a toggle or a
# choice); every command a property calls is a method of the wrapped class (the Python package
# wraps the same headers), so a typo cannot wait for a user to find it.
# Usage: PYTHONPATH=<build>/lib/python3/dist-packages python3 check_proxy_xml.py ASRT.xml
import sys
import xml.etree.ElementTree as ET

import asrt

NUMBER_DOMAINS = {"IntRangeDomain", "DoubleRangeDomain", "BooleanDomain", "EnumerationDomain"}
problems = []
proxies = 0
for group in ET.parse(sys.argv[1]).getroot():
    for proxy in group:
        proxies += 1
        name, class_name = proxy.get("name"), proxy.get("class")
        cls = getattr(asrt, class_name, None)
        if cls is None:
            problems.append(f"{name}: no class {class_name} in the package asrt")
            continue
        doc = proxy.find("Documentation")
        if doc is None or not (doc.text or "").strip() or not doc.get("short_help"):
            problems.append(f"{name}: no documentation (text and short_help)")
        for prop in proxy:
            if not prop.tag.endswith("Property"):
                continue
            where = f"{name}.{prop.get('name')}"
            doc = prop.find("Documentation")
            if doc is None or not (doc.text or "").strip():
                problems.append(f"{where}: no documentation")
            for attribute in ("command", "clean_command"):
                method = prop.get(attribute)
                if method and not hasattr(cls, method):
                    problems.append(f"{where}: {class_name} has no method {method}")
            if prop.get("information_only") == "1":
                continue
            domains = {child.tag for child in prop}
            if prop.tag in ("IntVectorProperty", "DoubleVectorProperty", "IdTypeVectorProperty"):
                if not domains & NUMBER_DOMAINS:
                    problems.append(f"{where}: a number without a range, toggle or choice")
                for rng in prop.findall("IntRangeDomain") + prop.findall("DoubleRangeDomain"):
                    count = int(prop.get("number_of_elements_per_command") or
                                prop.get("number_of_elements") or 1)
                    for bound in ("min", "max"):
                        values = (rng.get(bound) or "").split()
                        if values and count and len(values) not in (1, count):
                            problems.append(f"{where}: {bound} has {len(values)} values for "
                                            f"{count} elements")
            if prop.tag == "InputProperty" and "DataTypeDomain" not in domains:
                problems.append(f"{where}: an input without a data type")
if proxies < 5:
    problems.append(f"only {proxies} proxies: the source, scene geometry, reader, interpolator "
                    "and writer are expected")
for p in problems:
    print("FAIL:", p)
print(f"check_proxy_xml: {proxies} proxies, {len(problems)} problems")
sys.exit(1 if problems else 0)
