/* SPDX-License-Identifier: MIT */
/* xml_impl.h: private to formats/xml.c and formats/xml_read.c. */
#ifndef BTDF_FORMATS_XML_IMPL_H
#define BTDF_FORMATS_XML_IMPL_H

#include <stddef.h>

#include "btdf_radiance.h"

/* The .xml at path, read whole and parsed by btdf_rad_read_mem (xml_read.c). */
btdf_status xml_read(const char *path, btdf_rad **out, char *msg, size_t msglen);

#endif
