"""The Figure-8 plot carries readable numbers and a legend, drawn with the built-in pixel font."""

from __future__ import annotations

import numpy as np

from core.io.png_plot import BLACK, BLUE, RED, draw_text, scatter_image, text_width


def test_text_is_drawn_where_asked_and_nowhere_else():
    img = np.full((20, 40, 3), 255, dtype=np.uint8)
    draw_text(img, 2, 3, "10", scale=2)
    ink = np.argwhere((img == BLACK).all(axis=2))
    assert ink.size
    assert ink[:, 0].min() >= 3 and ink[:, 0].max() < 3 + 10
    assert ink[:, 1].min() >= 2 and ink[:, 1].max() < 2 + text_width("10", 2)
    # "1" and "0" differ: the glyphs are not blank boxes
    assert not np.array_equal(img[3:13, 2:8], img[3:13, 10:16])


def test_text_at_the_edge_is_clipped_not_an_error():
    img = np.full((10, 10, 3), 255, dtype=np.uint8)
    draw_text(img, 8, 8, "VIRTUAL SCALE")
    draw_text(img, -20, -20, "0.5")


def test_plot_has_tick_labels_and_a_legend_in_the_series_colours():
    rng = np.random.default_rng(1)
    actual = np.linspace(1.0, 0.8, 120)
    img = scatter_image([(actual, RED), (actual + rng.normal(0, 0.01, 120), BLUE)], labels=("actual", "estimated"),
                        x_title="frame", y_title="virtual scale")
    margin = 50
    left_strip = img[:, : margin - 6]
    assert (left_strip == BLACK).all(axis=2).sum() > 50          # y tick values
    below = img[-40:, margin:]
    assert (below == BLACK).all(axis=2).sum() > 50                # x tick values and title
    top = img[:16]
    assert (top == RED).all(axis=2).any() and (top == BLUE).all(axis=2).any()   # legend swatches
