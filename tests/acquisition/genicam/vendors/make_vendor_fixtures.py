#!/usr/bin/env python3
"""Real vendors' GenICam files served by Aravis's fake camera (arv-fake-gv-camera-0.8 -g FILE).

The fake camera has 64 KiB of register memory (0x0000-0xffff) and acts on a few registers of its
own (width 0x100, height 0x104, pixel format 0x128, acquisition 0x124, frame-start trigger mode
0x300, trigger source 0x304, software trigger 0x30c, ...). A vendor's file addresses registers
anywhere in 32 bits. This script moves only the register addresses:

  * every register address of 0x10000 and above (an <Address> of a register on the Device port,
    an address constant in a formula or an <Integer> value that a <pAddress> reads) is moved into
    the fake camera's free memory, 256-byte block by block, keeping each run of neighbouring
    blocks together (so base + selector * stride arithmetic still lands where the vendor meant);
  * addresses below 0x10000 (the GigE Vision bootstrap registers, which the fake camera serves)
    stay where they are;
  * the few registers that drive the fake camera are wired onto its own addresses (WIRING).

Every node, formula, selector, enumeration, tooltip and byte of the file is otherwise kept as the
vendor wrote it. The fake camera's memory starts zeroed, while a real camera powers up with its
limits in place; each fixture therefore comes with a `.powerup` list (address, 32-bit word) that
the test writes into the camera before anyone opens it: the inquiry bits of what the file
declares, the model's values (POWERUP), its names (IDENTITY), and 1 at 0x304: the fake camera
only frames software triggers when its trigger-source register reads 1, whatever value the
vendor gave Software. Each generated file is checked against its source: the same elements,
attributes and texts but for the addresses moved (check_only_addresses_moved).

Usage: make_vendor_fixtures.py ADGENICAM_XML_DIR OUT.tar.xz
  ADGENICAM_XML_DIR: the xml/ folder of https://github.com/areaDetector/ADGenICam (SOURCES
  names the files and the SHA-1 of the git blob each fixture was made from).
"""
import hashlib
import io
import re
import struct
import sys
import tarfile
import xml.etree.ElementTree as ET

FAKE_MEMORY_END = 0x10000
FIRST_FREE_BLOCK = 0x10  # 0x0000-0x0fff: bootstrap and the fake camera's own registers
# An inquiry register read whole: its top bits say implemented and available (Basler's layout).
INQUIRY_WORD = 0xC0000000
TRIGGER_SOURCE_SOFTWARE = (0x304, 1)  # the fake camera's trigger source register on Software

# fixture name: (ADGenICam file, git blob SHA-1 at ADGenICam ba5b9b8)
SOURCES = {
    "basler_aca1300_60gm": ("Basler-acA1300-60gm.xml", "a519fb03f0616534db8330b4f0a81723158faf1c"),
    "flir_bfs_pge_19s4m": ("FLIR_BFS_PGE_19S4M.xml", "0d3506494b166235f3b6dd07528aab510ad0fe25"),
    "avt_mako_g125b": ("AVT_Mako_G125B.xml", "b010d6951d94a6f9e0406423bcea8b5b1dd31829"),
    "dalsa_shadobox": ("Teledyne_ShadoBox.xml", "1262ad6ea06a25c71e1654f36d9fffb43ef2c541"),
}

# The registers wired onto the fake camera's own: (node, None, fake address) moves a register's
# literal <Address>; (formula node, constant as written, new constant) moves one address constant
# of a formula (the entry the frame-start selector picks).
WIRING = {
    "basler_aca1300_60gm": [
        ("N336", None, 0x100),  # Width
        ("N343", None, 0x104),  # Height
        ("N350", None, 0x130),  # OffsetX
        ("N357", None, 0x134),  # OffsetY
        ("N412", None, 0x124),  # AcquisitionStart writes 1 ...
        ("N413", None, 0x124),  # ... AcquisitionStop 0: the fake camera's acquisition register
        ("N1600", "0x40204", 0x300),  # TriggerMode, TriggerSelector FrameStart
        ("N1610", "0x40224", 0x30C),  # TriggerSoftware, FrameStart
        # PixelFormat stays off 0x128: its register holds Basler's own code (IntConverter N171),
        # not the PFNC value the fake camera sizes frames by; the fake camera sends Mono8.
    ],
    "flir_bfs_pge_19s4m": [
        ("Width_Val", None, 0x100),
        ("Height_Val", None, 0x104),
        ("OffsetX_Val", None, 0x130),
        ("OffsetY_Val", None, 0x134),
        ("PixelFormat_Val", None, 0x128),
        ("AcquisitionStart_Val", None, 0x124),  # AcquisitionStop writes 1 to a register of its
        # own: the fake camera never sees a stop (it stops when the controller leaves)
        # base + 0x20 * index + 4, FrameStart index 1 (TriggerSelectorValueToIndex)
        ("TriggerModeAddr", "0x000C8400", 0x300 - 0x20 - 4),
        ("TriggerSoftwareAddr", "0x000C8800", 0x30C - 0x20 - 4),
    ],
    "avt_mako_g125b": [
        ("RegWidth", None, 0x100),
        ("RegHeight", None, 0x104),
        ("RegRegionX", None, 0x130),
        ("RegRegionY", None, 0x134),
        ("RegPixelFormat", None, 0x128),
        ("RegAcquisitionCommand", None, 0x124),  # 1 start, 0 stop
        ("RegTriggerMode", None, 0x300),  # + 64 * selector, FrameStart 0
        ("RegSoftwareTrigger", None, 0x30C),
    ],
    "dalsa_shadobox": [],  # no trigger: nothing to wire but what irdist refuses anyway
}

# Power-up values a real camera of the model holds (its sensor, limits and the state its vendor
# ships), by register node, written before anyone opens the fake camera.
POWERUP = {
    "basler_aca1300_60gm": {
        "N336": 1280, "N343": 1024,  # Width, Height: the whole 1280 x 1024 sensor
        "N337": 1, "N338": 1280, "N339": 1, "N344": 1, "N345": 1024, "N346": 1,
        "N351": 0, "N352": 1279, "N353": 1, "N358": 0, "N359": 1023, "N360": 1,
        "N216": 1280, "N218": 1024,  # SensorWidth, SensorHeight
        "N1156": 1,  # PixelFormat: Basler's code of Mono8
        "N706": 1280 * 1024 * 2,  # PayloadSize: the largest frame (16-bit formats)
        # ExposureTimeRaw 500 steps of the 20 us timebase (N1129 on, N1128 in ns): 10 ms
        "N472": 500, "N473": 1, "N474": 50000, "N475": 1, "N1129": 1, "N1128": 20000,
        "N1355": 0, "N1357": 0, "N1359": 500, "N1366": 1,  # GainRaw
        "N119": 32, "N120": 0, "N121": 255,  # BlackLevelRaw
        "N754": 220, "N755": 16404,  # GevSCPSPacketSize bounds
    },
    "flir_bfs_pge_19s4m": {
        "Width_Val": 1600, "Height_Val": 1200,  # the whole 1600 x 1200 sensor
        "Width_Min": 8, "Width_Max": 1600, "Width_Inc": 8,
        "Height_Min": 2, "Height_Max": 1200, "Height_Inc": 2,
        "OffsetX_Min": 0, "OffsetX_Max": 1592, "OffsetX_Inc": 4,
        "OffsetY_Min": 0, "OffsetY_Max": 1198, "OffsetY_Inc": 2,
        "WidthMax_Val": 1600, "HeightMax_Val": 1200,
        "PixelFormat_Val": 0x01080001,  # Mono8
        "PayloadSize_Val": 1600 * 1200 * 2,
        "ExposureTime_Val": 10000, "ExposureTime_Min": 5, "ExposureTime_Max": 30000000,
        "GevSCPS_Min": 576, "GevSCPS_Max": 9000,
        "ExposureMode_Val": 1,  # Timed
    },
    "avt_mako_g125b": {
        "RegWidth": 1292, "RegHeight": 964,  # the whole 1292 x 964 sensor
        "RegWidthInc": 1, "RegHeightInc": 1, "RegMaxWidth": 1292, "RegMaxHeight": 964,
        "RegSensorWidth": 1292, "RegSensorHeight": 964,
        "RegPixelFormat": 0x01080001,  # Mono8
        "RegPayloadSize": 1292 * 964 * 2,
        "RegExposureValue": 10000, "RegExposureValueMin": 12, "RegExposureValueMax": 60000000,
        "RegExposureAuto": 1, "RegGainMode": 1, "RegAcquisitionMode": 1,  # Off, Off, Continuous
        "RegGainValueMin": 0, "RegGainValueMax": 32,
        "RegGammaValue": 1.0, "RegGammaMin": 0.45, "RegGammaMax": 1.0,
    },
    "dalsa_shadobox": {"pPixelFormatReg": 0x010C0006},  # Mono12Packed
}


# The bootstrap's manufacturer and model names (0x48, 0x68, 32 bytes each) as the camera says them.
IDENTITY = {
    "basler_aca1300_60gm": ("Basler", "acA1300-60gm"),
    "flir_bfs_pge_19s4m": ("FLIR", "Blackfly S BFS-PG-19S4M"),
    "avt_mako_g125b": ("Allied Vision Technologies", "Mako G-125B"),
    "dalsa_shadobox": ("Teledyne DALSA", "Shad-o-Box HS"),
}


class Vendor:
    """A vendor file: its raw text (edited in place) and its parsed node table."""

    def __init__(self, text):
        self.text = text
        root = ET.fromstring(text.encode("utf-8"))
        self.ns = re.match(r"\{.*\}", root.tag).group(0)
        self.nodes = {e.get("Name"): e for e in root.iter()
                      if e.get("Name") and e.tag != self.ns + "EnumEntry"}

    def tag(self, node):
        return node.tag[len(self.ns):]

    def children(self, node, name):
        return [c.text.strip() for c in node.findall(self.ns + name)]

    def on_device(self, node):
        port = self.children(node, "pPort")
        return port == ["Device"]


def is_mask(value):
    return value >= 0xF0000000 or (value & (value + 1)) == 0


def address_formula_nodes(vendor):
    """The formula and <Integer> nodes whose values are register addresses (read by pAddress)."""
    found, stack = set(), []
    for node in vendor.nodes.values():
        if vendor.on_device(node):
            stack += vendor.children(node, "pAddress")
    while stack:
        name = stack.pop()
        if name in found:
            continue
        found.add(name)
        node = vendor.nodes[name]
        if vendor.tag(node) in ("IntSwissKnife", "SwissKnife"):
            stack += vendor.children(node, "pVariable")
        elif vendor.tag(node) == "Integer":
            stack += vendor.children(node, "pValue")
    return found


def constants(text):
    return re.findall(r"0[xX][0-9A-Fa-f]+|\b[0-9]+\b", text)


def address_atoms(vendor, formula_nodes):
    """(address, extent) of every moved address: literal registers and formula constants."""
    atoms = []
    for name, node in vendor.nodes.items():
        literals = [int(a, 0) for a in vendor.children(node, "Address")]
        if literals and vendor.on_device(node) and sum(literals) >= FAKE_MEMORY_END:
            length = vendor.children(node, "Length")
            atoms.append((sum(literals), int(length[0], 0) if length else 4))
        if name in formula_nodes:
            field = "Formula" if vendor.tag(node) != "Integer" else "Value"
            for text in vendor.children(node, field):
                for c in constants(text):
                    value = int(c, 0)
                    if value >= FAKE_MEMORY_END and not is_mask(value):
                        atoms.append((value, 0x100))  # room for selector strides
    return atoms


def block_map(atoms):
    """Original 256-byte block -> new block, runs of neighbouring blocks kept together."""
    blocks = sorted({b for address, extent in atoms
                     for b in range(address >> 8, ((address + extent - 1) >> 8) + 1)})
    runs = []
    for block in blocks:
        if runs and block - runs[-1][-1] <= 2:
            runs[-1].extend(range(runs[-1][-1] + 1, block + 1))
        else:
            runs.append([block])
    mapping, next_block = {}, FIRST_FREE_BLOCK
    for run in runs:
        for i, block in enumerate(run):
            mapping[block] = next_block + i
        next_block += len(run)
    if next_block > FAKE_MEMORY_END >> 8:
        raise SystemExit(f"registers need {next_block - FIRST_FREE_BLOCK} blocks of 256 bytes, "
                         f"the fake camera has {(FAKE_MEMORY_END >> 8) - FIRST_FREE_BLOCK}")
    return mapping


def moved(mapping, address):
    return (mapping[address >> 8] << 8) | (address & 0xFF)


def node_span(vendor, name):
    """Start and end of the node's element in the raw text."""
    match = re.search(r'<(\w+)\s+Name="%s"[\s>/]' % re.escape(name), vendor.text)
    if match is None:
        raise SystemExit(f"node {name} not found")
    end = vendor.text.find("</%s>" % match.group(1), match.end())
    return match.start(), end


def apply_edits(vendor, edits):
    """Applies {node: [edit(text) -> text]} to the top-level nodes in one pass over the text."""
    out, position = [], 0
    for match in re.finditer(r'<(\w+)\s+Name="([^"]+)"', vendor.text):
        if match.start() < position or match.group(2) not in edits:
            continue
        end = vendor.text.find("</%s>" % match.group(1), match.end())
        body = vendor.text[match.start():end]
        for edit in edits.pop(match.group(2)):
            body = edit(body)
        out += [vendor.text[position:match.start()], body]
        position = end
    if edits:
        raise SystemExit(f"nodes not found: {sorted(edits)}")
    vendor.text = "".join(out) + vendor.text[position:]


def set_address(body, new_address):
    addresses = re.findall(r"<Address>\s*([^<]+?)\s*</Address>", body)
    if len(addresses) != 1:
        raise SystemExit(f"expected one <Address> in {body[:80]}")
    return re.sub(r"<Address>\s*[^<]+?\s*</Address>", "<Address>0x%X</Address>" % new_address,
                  body, count=1)


def move_constants(body, element, mapping):
    def one(match):
        value = int(match.group(0), 0)
        if value < FAKE_MEMORY_END or is_mask(value):
            return match.group(0)
        return "0x%X" % moved(mapping, value)

    def inside(match):
        return match.group(1) + re.sub(r"0[xX][0-9A-Fa-f]+|\b[0-9]+\b", one, match.group(2)) + \
            match.group(3)
    return re.sub(r"(<%s>)(.*?)(</%s>)" % (element, element), inside, body, flags=re.S)


def relocate(vendor, mapping, formula_nodes, edits):
    for name, node in vendor.nodes.items():
        literals = [int(a, 0) for a in vendor.children(node, "Address")]
        if literals and vendor.on_device(node) and sum(literals) >= FAKE_MEMORY_END:
            if len(literals) != 1:
                raise SystemExit(f"{name}: several <Address> adding up past 64 KiB")
            new_address = moved(mapping, literals[0])
            edits.setdefault(name, []).append(lambda b, a=new_address: set_address(b, a))
        if name in formula_nodes:
            field = "Formula" if vendor.tag(node) != "Integer" else "Value"
            edits.setdefault(name, []).append(
                lambda b, f=field: move_constants(b, f, mapping))


def wire(wiring, mapping, edits):
    for name, constant, fake_address in wiring:
        if constant is None:
            edits.setdefault(name, []).append(lambda b, a=fake_address: set_address(b, a))
            continue
        moved_text = "0x%X" % moved(mapping, int(constant, 0))

        def swap(body, name=name, moved_text=moved_text, fake_address=fake_address):
            if body.count(moved_text) != 1:
                raise SystemExit(f"{name}: {moved_text} is not there once")
            return body.replace(moved_text, "0x%X" % fake_address)
        edits.setdefault(name, []).append(swap)


def register_field(vendor, name):
    """(address, length, shift, width, little endian) of a register node or one of its fields."""
    start, end = node_span(vendor, name)
    body = vendor.text[start:end]

    def tag(element):
        match = re.search(r"<%s>\s*([^<]+?)\s*</%s>" % (element, element), body)
        return int(match.group(1), 0) if match else None
    address, length = tag("Address"), tag("Length") or 4
    little = "LittleEndian" in body
    indirect = re.search(r"<pAddress>\s*([^<]+?)\s*</pAddress>", body)
    if indirect is not None:
        # every address the formula can give (each selector entry's), plus the literal offset
        start, end = node_span(vendor, indirect.group(1))
        numbers = [int(c, 0) for c in constants(vendor.text[start:end])]
        strides = [n for n in numbers if 4 <= n < 0x100 and n % 4 == 0] or [0]
        address = sorted({(address or 0) + base + stride * i for base in numbers
                          if base >= 0x100 for stride in strides for i in range(4)})
    bit, lsb, msb = tag("Bit"), tag("LSB"), tag("MSB")
    if bit is not None:
        lsb = msb = bit
    if lsb is None:
        return address, length, 0, 8 * length, little  # address: a number or a list
    low, high = (min(lsb, msb), max(lsb, msb)) if little else (max(lsb, msb), min(lsb, msb))
    shift = low if little else 8 * length - 1 - low
    return address, length, shift, abs(high - low) + 1, little


def inquiry_registers(vendor):
    """The registers behind a pIsImplemented or pIsAvailable: a camera's inquiry bits, which
    report what it implements. Read-only ones, or any a formula reads (a register named directly
    and writable is a feature's value, e.g. ChunkModeActive)."""
    stack, seen, found = [], set(), {}
    for node in vendor.nodes.values():
        for element in node.iter():
            for child in ("pIsImplemented", "pIsAvailable"):
                stack += [(ref.text.strip(), True) for ref in element.findall(vendor.ns + child)]
    while stack:
        name, direct = stack.pop()
        node = vendor.nodes.get(name)
        if (name, direct) in seen or node is None:
            continue
        seen.add((name, direct))
        tag = vendor.tag(node)
        if tag in ("MaskedIntReg", "IntReg"):
            if vendor.children(node, "AccessMode") == ["RO"] or not direct:
                found[name] = None if tag == "MaskedIntReg" else INQUIRY_WORD
        elif tag in ("IntSwissKnife", "SwissKnife", "Integer", "IntConverter", "Converter"):
            stack += [(ref, False) for ref in
                      vendor.children(node, "pVariable") + vendor.children(node, "pValue")]
    return found


def powerup_words(vendor, values):
    """{address: 32-bit word as the fake camera holds it (big-endian)}: every inquiry bit set
    (a camera reports what it implements), then the model's values."""
    words = {}
    fields = [(n, v, True) for n, v in sorted(inquiry_registers(vendor).items())]
    fields += [(n, v, False) for n, v in values.items()]
    for name, value, inquiry in fields:
        addresses, length, shift, width, little = register_field(vendor, name)
        for address in addresses if isinstance(addresses, list) else [addresses]:
            if address is None or length != 4 or not 0x100 <= address < FAKE_MEMORY_END or \
                    (inquiry and (address < 0x240 or address in (0x300, 0x304, 0x30C))):
                continue  # never the bootstrap or the fake camera's own registers
            if isinstance(value, float):
                value = struct.unpack(">I", struct.pack(">f", value))[0]
            mask = ((1 << width) - 1) << shift
            field = mask if value is None else (value << shift) & mask
            order = "little" if little else "big"
            word = int.from_bytes(words.get(address, 0).to_bytes(4, "big"), order)
            word = (word & ~mask) | field
            words[address] = int.from_bytes(word.to_bytes(4, order), "big")
    return words


def check_only_addresses_moved(original, generated, formula_nodes):
    """Raises unless the two files differ only in <Address> texts and in the formulas and values
    of the address nodes."""
    def texts(text):
        root = ET.fromstring(text.encode("utf-8"))
        for node in root.iter():
            name = node.get("Name", "")
            for child in node:
                kind = child.tag.split("}")[-1]
                moved_text = kind == "Address" or (name in formula_nodes and
                                                   kind in ("Formula", "Value"))
                yield child.tag, sorted(child.attrib.items()), \
                    None if moved_text else (child.text or "").strip()
    before, after = list(texts(original)), list(texts(generated))
    if len(before) != len(after):
        raise SystemExit(f"{len(before)} elements became {len(after)}")
    for old, new in zip(before, after):
        if old != new:
            raise SystemExit(f"changed beyond an address: {old} -> {new}")


def make_fixture(xml_dir, fixture):
    file_name, blob_sha1 = SOURCES[fixture]
    with open(f"{xml_dir}/{file_name}", "rb") as f:
        data = f.read()
    actual = hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()
    if actual != blob_sha1:
        raise SystemExit(f"{file_name}: git blob {actual}, expected {blob_sha1}")
    vendor = Vendor(data.decode("utf-8"))
    formula_nodes = address_formula_nodes(vendor)
    mapping = block_map(address_atoms(vendor, formula_nodes))
    edits = {}
    relocate(vendor, mapping, formula_nodes, edits)
    wire(WIRING[fixture], mapping, edits)
    apply_edits(vendor, edits)
    check_only_addresses_moved(data.decode("utf-8"), vendor.text, formula_nodes)
    lines = ["# address word: written big-endian before the camera is opened (%s)" % file_name]
    words = powerup_words(vendor, POWERUP[fixture])
    words[TRIGGER_SOURCE_SOFTWARE[0]] = TRIGGER_SOURCE_SOFTWARE[1]
    for address, text in zip((0x48, 0x68), IDENTITY[fixture]):
        padded = text.encode("ascii").ljust(32, b"\0")
        for i in range(0, 32, 4):
            words[address + i] = int.from_bytes(padded[i:i + 4], "big")
    lines += ["0x%X 0x%08X" % item for item in sorted(words.items())]
    return vendor.text.encode("utf-8"), ("\n".join(lines) + "\n").encode("utf-8")


def main(argv):
    if len(argv) != 3:
        raise SystemExit(__doc__)
    with tarfile.open(argv[2], "w:xz") as tar:
        for fixture in SOURCES:
            xml, powerup = make_fixture(argv[1], fixture)
            for suffix, content in ((".xml", xml), (".powerup", powerup)):
                info = tarfile.TarInfo(fixture + suffix)
                info.size, info.mtime, info.mode = len(content), 0, 0o644
                tar.addfile(info, io.BytesIO(content))


if __name__ == "__main__":
    main(sys.argv)
