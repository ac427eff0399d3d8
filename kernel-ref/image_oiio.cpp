/*
 * image_oiio.cpp: image.h on OpenImageIO 2.4, the only C++ in saarsim.
 *
 * A thin extern "C" shim: img_write writes to "<path>.tmp<pid>.<ext>" in the
 * target's folder (OIIO picks the format from the extension) and renames it
 * into place, so a reader never sees a half-written image; img_read_rgba8
 * reads any OIIO format and widens or narrows it to RGBA8. No exception
 * leaves this file: C callers only see -1 and a diag.
 */
/* diag.h has no extern "C" guard of its own; include it with C linkage
 * first so the include in image.h is a no-op. */
extern "C" {
#include "diag.h"
}
#include "image.h"

#include <OpenImageIO/imageio.h>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <unistd.h>
#include <vector>

using namespace OIIO;

static std::string lower_ext(const char *path)
{
	const char *slash = std::strrchr(path, '/');
	const char *dot = std::strrchr(slash ? slash : path, '.');
	std::string e = dot ? dot + 1 : "";
	for (char &c : e)
		c = (char)std::tolower((unsigned char)c);
	return e;
}

/* OIIO keeps its last error per thread or per object; take one line of it. */
static std::string one_line(std::string s)
{
	size_t nl = s.find('\n');
	if (nl != std::string::npos)
		s.resize(nl);
	return s.empty() ? "unknown OpenImageIO error" : s;
}

static int write_tmp(const std::string &tmp, const std::string &ext, int w, int h,
                     const uint8_t *rgb8, const float *rgbf, std::string &err)
{
	auto out = ImageOutput::create(tmp);
	if (!out) {
		err = "no image writer for extension '." + ext + "': " + one_line(OIIO::geterror());
		return -1;
	}
	bool is_float = ext == "exr" || ext == "hdr";
	/* Float formats store half floats; an 8-bit source is converted by
	 * OIIO's normalised conversion (v/255), which suffices for previews. */
	ImageSpec spec(w, h, 3, is_float ? TypeDesc::HALF : TypeDesc::UINT8);
	if (!out->open(tmp, spec)) {
		err = one_line(out->geterror());
		return -1;
	}
	bool ok = (is_float && rgbf) ? out->write_image(TypeDesc::FLOAT, rgbf)
	                             : out->write_image(TypeDesc::UINT8, rgb8);
	if (!ok)
		err = one_line(out->geterror());
	if (!out->close() && ok) {
		err = one_line(out->geterror());
		ok = false;
	}
	return ok ? 0 : -1;
}

extern "C" int img_write(const char *path, int w, int h, const uint8_t *rgb8, const float *rgbf,
                         diag *d)
{
	if (w <= 0 || h <= 0 || (!rgb8 && !rgbf))
		return diag_set(d, path, 0, 0, "cannot write a %dx%d image without pixels", w, h);
	try {
		std::string ext = lower_ext(path);
		std::string tmp =
		    std::string(path) + ".tmp" + std::to_string((long)getpid()) + "." + ext;
		std::vector<uint8_t> conv;
		if (!rgb8) {
			/* Only a float buffer was given but the format is 8-bit:
			 * clamp and quantise here. */
			conv.resize((size_t)w * h * 3);
			for (size_t i = 0; i < conv.size(); i++) {
				float v = rgbf[i];
				v = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;
				conv[i] = (uint8_t)(v * 255.0f + 0.5f);
			}
			rgb8 = conv.data();
		}
		std::string err;
		if (write_tmp(tmp, ext, w, h, rgb8, rgbf, err) != 0) {
			std::remove(tmp.c_str());
			return diag_set(d, path, 0, 0, "cannot write image: %s", err.c_str());
		}
		if (std::rename(tmp.c_str(), path) != 0) {
			int e = errno;
			std::remove(tmp.c_str());
			return diag_set(d, path, 0, 0, "cannot write image: rename: %s",
			                std::strerror(e));
		}
		return 0;
	} catch (const std::exception &e) {
		return diag_set(d, path, 0, 0, "cannot write image: %s", e.what());
	}
}

extern "C" int img_read_rgba8(const char *path, int *w, int *h, uint8_t **rgba, diag *d)
{
	*rgba = nullptr;
	try {
		auto in = ImageInput::open(path);
		if (!in)
			return diag_set(d, path, 0, 0, "cannot read image: %s",
			                one_line(OIIO::geterror()).c_str());
		const ImageSpec &spec = in->spec();
		int iw = spec.width, ih = spec.height, nc = spec.nchannels;
		if (iw <= 0 || ih <= 0 || nc <= 0 || (long long)iw * ih > (1LL << 28))
			return diag_set(d, path, 0, 0,
			                "unsupported image size %dx%d with %d channels", iw, ih,
			                nc);
		std::vector<uint8_t> px((size_t)iw * ih * nc);
		if (!in->read_image(0, 0, 0, nc, TypeDesc::UINT8, px.data())) {
			std::string e = one_line(in->geterror());
			return diag_set(d, path, 0, 0, "cannot read image: %s", e.c_str());
		}
		in->close();
		uint8_t *out = (uint8_t *)std::malloc((size_t)iw * ih * 4);
		if (!out)
			return diag_set(d, path, 0, 0, "out of memory reading image");
		/* Grey (1), grey+alpha (2), RGB (3), RGBA and beyond (4+). */
		for (size_t i = 0; i < (size_t)iw * ih; i++) {
			const uint8_t *s = &px[i * nc];
			uint8_t *o = out + 4 * i;
			o[0] = s[0];
			o[1] = nc >= 3 ? s[1] : s[0];
			o[2] = nc >= 3 ? s[2] : s[0];
			o[3] = nc == 2 ? s[1] : nc >= 4 ? s[3] : 255;
		}
		*w = iw;
		*h = ih;
		*rgba = out;
		return 0;
	} catch (const std::exception &e) {
		return diag_set(d, path, 0, 0, "cannot read image: %s", e.what());
	}
}
