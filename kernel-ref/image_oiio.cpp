/*
 * image_oiio.cpp: the OpenImageIO plugin (libsaar-oiio.so), the only C++ in
 * saarsim. It writes and reads one image file each call (image_plugin.h);
 * temporary names, renames and diagnostics are image.c's. No exception
 * leaves this file: the C side only sees -1 and one line of text.
 */
#include "kernel-ref/image_plugin.h"

#include <OpenImageIO/imageio.h>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

using namespace OIIO;

/* OIIO keeps its last error per thread or per object; take one line of it. */
static std::string one_line(std::string s)
{
	size_t nl = s.find('\n');
	if (nl != std::string::npos)
		s.resize(nl);
	return s.empty() ? "unknown OpenImageIO error" : s;
}

static int fail(char *err, size_t errlen, const std::string &what)
{
	std::snprintf(err, errlen, "%s", what.c_str());
	return -1;
}

/* Reads back the file write_spec has just closed: the whole image, of
 * spec's size and channels, and for 8-bit pixels the very bytes written.
 * A writer can "succeed" on a file cut short: OpenImageIO's PNG writer
 * took no notice of a failed write (the file-size limit), so a truncated
 * PNG was renamed into place with exit status 0. */
static int read_back(const char *path, const char *ext_c, const ImageSpec &spec, TypeDesc type,
                     const void *px, char *err, size_t errlen)
{
	auto in = ImageInput::open(path);
	if (!in)
		return fail(err, errlen,
		            "written file does not read back: " + one_line(OIIO::geterror()));
	const ImageSpec &got = in->spec();
	if (got.width != spec.width || got.height != spec.height || got.nchannels != spec.nchannels)
		return fail(err, errlen, "written file reads back as another image");
	size_t n = (size_t)spec.width * (size_t)spec.height * (size_t)spec.nchannels;
	std::vector<uint8_t> back(n * type.size());
	if (!in->read_image(0, 0, 0, spec.nchannels, type, back.data()) || in->has_error())
		return fail(err, errlen,
		            "written file does not read back: " + one_line(in->geterror()));
	in->close();
	/* png, ppm and tif keep 8-bit pixels exactly; floats were stored as
	 * halves and JPEG is lossy, so of those only the reading back is
	 * checked */
	std::string ext = ext_c;
	bool exact = ext == "png" || ext == "ppm" || ext == "tif" || ext == "tiff";
	if (exact && type == TypeDesc::UINT8 && spec.format == TypeDesc::UINT8 &&
	    std::memcmp(back.data(), px, n) != 0)
		return fail(err, errlen, "written file reads back with other pixels");
	return 0;
}

/* Writes one image of `spec` from pixels px of type `type`: create,
 * open, write, close, read back (read_back), each error one line. Both
 * writers below end here. */
static int write_spec(const char *path, const char *ext_c, const ImageSpec &spec, TypeDesc type,
                      const void *px, char *err, size_t errlen)
{
	try {
		auto out = ImageOutput::create(path);
		if (!out)
			return fail(err, errlen,
			            std::string("no image writer for extension '.") + ext_c +
			                "': " + one_line(OIIO::geterror()));
		if (!out->open(path, spec))
			return fail(err, errlen, one_line(out->geterror()));
		bool ok = out->write_image(type, px);
		std::string e = ok ? "" : one_line(out->geterror());
		if (!out->close() && ok) {
			e = one_line(out->geterror());
			ok = false;
		}
		if (!ok)
			return fail(err, errlen, e);
		return read_back(path, ext_c, spec, type, px, err, errlen);
	} catch (const std::exception &x) {
		return fail(err, errlen, x.what());
	}
}

static int write_rgb(const char *path, const char *ext_c, int w, int h, const uint8_t *rgb8,
                     const float *rgbf, char *err, size_t errlen)
{
	try {
		std::string ext = ext_c;
		bool is_float = ext == "exr" || ext == "hdr";
		/* Float formats store half floats; an 8-bit source is converted by
		 * OIIO's normalised conversion (v/255), which suffices for previews. */
		ImageSpec spec(w, h, 3, is_float ? TypeDesc::HALF : TypeDesc::UINT8);
		if (is_float && rgbf)
			return write_spec(path, ext_c, spec, TypeDesc::FLOAT, rgbf, err, errlen);
		return write_spec(path, ext_c, spec, TypeDesc::UINT8, rgb8, err, errlen);
	} catch (const std::exception &x) {
		return fail(err, errlen, x.what());
	}
}

static int can_write(const char *path, char *err, size_t errlen)
{
	try {
		if (ImageOutput::create(path))
			return 0;
		return fail(err, errlen, "no image writer for it: " + one_line(OIIO::geterror()));
	} catch (const std::exception &x) {
		return fail(err, errlen, x.what());
	}
}

static int read_rgba8(const char *path, int *w, int *h, uint8_t **rgba, char *err, size_t errlen)
{
	*rgba = nullptr;
	try {
		auto in = ImageInput::open(path);
		if (!in)
			return fail(err, errlen, one_line(OIIO::geterror()));
		const ImageSpec &spec = in->spec();
		int iw = spec.width, ih = spec.height, nc = spec.nchannels;
		if (iw <= 0 || ih <= 0 || nc <= 0 || (long long)iw * ih > (1LL << 28))
			return fail(err, errlen,
			            "unsupported image size " + std::to_string(iw) + "x" +
			                std::to_string(ih) + " with " + std::to_string(nc) +
			                " channels");
		std::vector<uint8_t> px((size_t)iw * ih * nc);
		/* a file cut short can still "succeed": libjpeg fills the
		 * missing scanlines with grey and OpenImageIO keeps its warning
		 * as a pending error, so a pending error fails the read too */
		if (!in->read_image(0, 0, 0, nc, TypeDesc::UINT8, px.data()) || in->has_error())
			return fail(err, errlen, one_line(in->geterror()));
		in->close();
		uint8_t *out = (uint8_t *)std::malloc((size_t)iw * ih * 4);
		if (!out)
			return fail(err, errlen, "out of memory");
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
	} catch (const std::exception &x) {
		return fail(err, errlen, x.what());
	}
}

static int write_y32f(const char *path, const char *ext_c, int w, int h, const float *v, char *err,
                      size_t errlen)
{
	try {
		ImageSpec spec(w, h, 1, TypeDesc::FLOAT);
		spec.channelnames = {"Y"};
		return write_spec(path, ext_c, spec, TypeDesc::FLOAT, v, err, errlen);
	} catch (const std::exception &x) {
		return fail(err, errlen, x.what());
	}
}

static const img_plugin plugin = {IMG_PLUGIN_ABI, write_rgb, can_write, read_rgba8, write_y32f};

/* No worker pools: OpenImageIO's own and OpenEXR's (which an EXR read or
 * write, or an EXR writer's creation, starts) would be threads the scene
 * importer's child process does not have, and an EXR texture read there
 * waited on them for good (importproc.c forked after rtref and saarsim
 * opened this plugin for --out; they open it after the import now, since
 * the libraries behind OIIO start threads of their own as they load:
 * image.h, img_reserve_file). Images are read and written on the calling
 * thread instead; saarsim's frames and textures are small. */
extern "C" const img_plugin *saar_image_plugin(void)
{
	static const bool serial = [] {
		OIIO::attribute("threads", 1);
		OIIO::attribute("exr_threads", -1);
		return true;
	}();
	(void)serial;
	return &plugin;
}
