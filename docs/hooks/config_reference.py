"""mkdocs hook: each ``<!-- config-reference: KIND -->`` marker becomes the config reference of that kind,
generated from the pydantic models (:func:`excite_cli.workflows.schema.reference_markdown`)."""

import re

from excite_cli.workflows.schema import reference_markdown


def on_page_markdown(markdown, page, config, files):
    return re.sub(r"<!-- config-reference: (\w+) -->", lambda m: reference_markdown(m.group(1)), markdown)
