"""Reading back what the Results panel lists."""


def listed_frames(text: str) -> set[int]:
    """The frames of ``core.confidence.frame_list``'s text (``3, 5-9, 12``)."""
    return {f for part in text.split(", ") if part
            for f in range(int(part.split("-")[0]), int(part.split("-")[-1]) + 1)}
