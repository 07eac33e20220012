"""What both scenes share: tab state, exact texts, drawing, the page, links, origins, the wire."""
