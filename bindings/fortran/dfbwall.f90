! dfbwall's Fortran module: the C API (<dfbwall/dfbwall.h>, libdfbwall.so) through iso_c_binding,
! for simulations written in Fortran (docs/insitu.md, "Fortran"). `use dfbwall`, link
! dfbwall::fortran (libdfbwall_fortran.a and libdfbwall.so) and MPI.
!
! The calls are the C API's, by the same names, with Fortran arguments: handles are derived types
! (type(dfbwall_session), ...), text is character, flags are logical, the communicator is an MPI
! integer handle (the old `mpi` module's, or mpi_f08's comm%MPI_VAL). Which calls are collective
! and what each error means on the other ranks are the C API's (dfbwall.h).
!
! Errors: every call that can fail takes an optional `status` (DFBWALL_OK = 0, else the C API's
! code; dfbwall_last_error() is the message). Without `status`, a failure writes the message to
! the error unit and stops (error stop): bad input is refused by the next render_frame on every
! render rank alike, so every rank stops with the same message.
!
! Bricks: dfbwall_brick_init, then one dfbwall_brick_add_volume per style volume (real(4),
! real(8), integer(1), integer(2), integer(4); integer(1) and (2) read as uint8/uint16 with
! unsigned=.true.), particles and a mesh; then dfbwall_session_add_brick, which reads the arrays.
! Fortran's column-major v(i,j,k) is the C API's x fastest, then y, then z: element v(i,j,k) of
! an array added at lo (0-based) is whole-field voxel lo + (i,j,k) - lbound(v). The arrays must be
! contiguous, have the TARGET (or POINTER) attribute and stay where they are until
! dfbwall_session_add_brick returns (it copies them).
module dfbwall
  use, intrinsic :: iso_c_binding
  use, intrinsic :: iso_fortran_env, only: error_unit
  implicit none
  private

  integer(c_int), parameter, public :: DFBWALL_GHOSTS_GIVEN = 0, DFBWALL_GHOSTS_EXCHANGE = 1
  integer, parameter, public :: DFBWALL_OK = 0, DFBWALL_ERROR_INPUT = 1, &
                                DFBWALL_ERROR_USAGE = 2, DFBWALL_ERROR_FAILED = 3, &
                                DFBWALL_ERROR_OUT_OF_MEMORY = 4, DFBWALL_ERROR_UNKNOWN = 5
  integer, parameter, public :: DFBWALL_LIGHT_DIRECTIONAL = 0, DFBWALL_LIGHT_POINT = 1, &
                                DFBWALL_LIGHT_AMBIENT = 2
  ! dfbwall_voxel_type
  integer(c_int), parameter :: FLOAT32 = 0, UINT8 = 1, UINT16 = 2, INT8 = 3, INT16 = 4, &
                               INT32 = 5, FLOAT64 = 6

  type, public :: dfbwall_options
    type(c_ptr) :: ptr = c_null_ptr
  end type
  type, public :: dfbwall_style
    type(c_ptr) :: ptr = c_null_ptr
  end type
  type, public :: dfbwall_session
    type(c_ptr) :: ptr = c_null_ptr
  end type

  ! The C structs (dfbwall_volume_part, dfbwall_brick), field for field.
  type, bind(c) :: volume_part_c
    integer(c_int) :: lo(3), hi(3)
    integer(c_int) :: type
    type(c_ptr) :: voxels
  end type
  type, bind(c) :: brick_c
    integer(c_int) :: id
    real(c_float) :: bounds_lo(3), bounds_hi(3)
    type(c_ptr) :: volumes
    integer(c_size_t) :: volume_count
    type(c_ptr) :: particle_centers
    integer(c_size_t) :: particle_count
    type(c_ptr) :: particle_radii
    integer(c_size_t) :: radius_count
    type(c_ptr) :: ghost_particle_centers
    integer(c_size_t) :: ghost_particle_count
    type(c_ptr) :: ghost_particle_radii
    integer(c_size_t) :: ghost_radius_count
    type(c_ptr) :: mesh_positions
    integer(c_size_t) :: mesh_position_count
    type(c_ptr) :: mesh_triangles
    integer(c_size_t) :: mesh_triangle_count
    type(c_ptr) :: ghost_mesh_positions
    integer(c_size_t) :: ghost_mesh_position_count
    type(c_ptr) :: ghost_mesh_triangles
    integer(c_size_t) :: ghost_mesh_triangle_count
    integer(c_int) :: ghosts  ! DFBWALL_GHOSTS_GIVEN or DFBWALL_GHOSTS_EXCHANGE
  end type

  ! What one rank holds: addresses of the program's arrays, read by dfbwall_session_add_brick.
  type, public :: dfbwall_brick
    private
    type(brick_c) :: c
    type(volume_part_c), allocatable :: parts(:)
    integer :: part_count = 0
    logical :: ready = .false.                ! dfbwall_brick_init was called
    character(len=:), allocatable :: problem  ! an array the C API cannot read
  end type

  public :: dfbwall_last_error, dfbwall_last_error_code, dfbwall_set_error_function
  public :: dfbwall_options_new, dfbwall_options_set, dfbwall_options_release
  public :: dfbwall_style_new, dfbwall_style_release, dfbwall_style_add_volume, &
            dfbwall_style_set_transfer_function, dfbwall_style_set_value_range, &
            dfbwall_style_set_volume_visible, dfbwall_style_add_isosurface, &
            dfbwall_style_add_light, dfbwall_style_set_particles, dfbwall_style_set_mesh, &
            dfbwall_style_set_ambient_occlusion, dfbwall_style_set_shadows, &
            dfbwall_style_set_sampling_rate, dfbwall_style_set_background, &
            dfbwall_style_set_samples_per_pixel, dfbwall_style_set_seed
  public :: dfbwall_brick_init, dfbwall_brick_add_volume, dfbwall_brick_add_no_volume, &
            dfbwall_brick_set_particles, dfbwall_brick_set_ghost_particles, &
            dfbwall_brick_set_mesh, dfbwall_brick_set_ghost_mesh
  public :: dfbwall_session_new, dfbwall_session_release, dfbwall_session_is_wall_rank, &
            dfbwall_session_render_comm, dfbwall_session_canvas_width, &
            dfbwall_session_canvas_height, dfbwall_session_run_wall, dfbwall_session_set_style, &
            dfbwall_session_add_brick, dfbwall_session_clear_bricks, dfbwall_session_set_camera, &
            dfbwall_session_render_frame, dfbwall_session_frames_rendered, dfbwall_session_image, &
            dfbwall_session_write_image, dfbwall_session_scene_bytes, dfbwall_session_close

  interface dfbwall_brick_add_volume
    module procedure add_volume_real4, add_volume_real8, add_volume_int1, add_volume_int2, &
      add_volume_int4
  end interface

  ! The C API.
  interface
    function c_strlen(s) bind(c, name="strlen")
      import :: c_ptr, c_size_t
      type(c_ptr), value :: s
      integer(c_size_t) :: c_strlen
    end function
    function c_last_error() bind(c, name="dfbwall_last_error")
      import :: c_ptr
      type(c_ptr) :: c_last_error
    end function
    function c_last_error_code() bind(c, name="dfbwall_last_error_code")
      import :: c_int
      integer(c_int) :: c_last_error_code
    end function
    subroutine c_set_error_function(handler, user) bind(c, name="dfbwall_set_error_function")
      import :: c_funptr, c_ptr
      type(c_funptr), value :: handler
      type(c_ptr), value :: user
    end subroutine
    function c_options_new(out) bind(c, name="dfbwall_options_new")
      import :: c_ptr, c_int
      type(c_ptr) :: out
      integer(c_int) :: c_options_new
    end function
    function c_options_set(options, key, value) bind(c, name="dfbwall_options_set")
      import :: c_ptr, c_int, c_char
      type(c_ptr), value :: options
      character(kind=c_char) :: key(*), value(*)
      integer(c_int) :: c_options_set
    end function
    subroutine c_options_release(options) bind(c, name="dfbwall_options_release")
      import :: c_ptr
      type(c_ptr), value :: options
    end subroutine
    function c_style_new(out) bind(c, name="dfbwall_style_new")
      import :: c_ptr, c_int
      type(c_ptr) :: out
      integer(c_int) :: c_style_new
    end function
    subroutine c_style_release(style) bind(c, name="dfbwall_style_release")
      import :: c_ptr
      type(c_ptr), value :: style
    end subroutine
    function c_style_add_volume(style, name, dims, origin, spacing, index) &
      bind(c, name="dfbwall_style_add_volume")
      import :: c_ptr, c_int, c_char, c_float
      type(c_ptr), value :: style
      character(kind=c_char) :: name(*)
      integer(c_int) :: dims(3), index
      real(c_float) :: origin(3), spacing(3)
      integer(c_int) :: c_style_add_volume
    end function
    function c_style_set_transfer_function(style, volume, preset, max_opacity) &
      bind(c, name="dfbwall_style_set_transfer_function")
      import :: c_ptr, c_int, c_char, c_float
      type(c_ptr), value :: style
      integer(c_int), value :: volume
      character(kind=c_char) :: preset(*)
      real(c_float), value :: max_opacity
      integer(c_int) :: c_style_set_transfer_function
    end function
    function c_style_set_value_range(style, volume, min, max) &
      bind(c, name="dfbwall_style_set_value_range")
      import :: c_ptr, c_int, c_float
      type(c_ptr), value :: style
      integer(c_int), value :: volume
      real(c_float), value :: min, max
      integer(c_int) :: c_style_set_value_range
    end function
    function c_style_set_volume_visible(style, volume, visible) &
      bind(c, name="dfbwall_style_set_volume_visible")
      import :: c_ptr, c_int
      type(c_ptr), value :: style
      integer(c_int), value :: volume, visible
      integer(c_int) :: c_style_set_volume_visible
    end function
    function c_style_add_isosurface(style, volume, value, color, opacity) &
      bind(c, name="dfbwall_style_add_isosurface")
      import :: c_ptr, c_int, c_float
      type(c_ptr), value :: style
      integer(c_int), value :: volume
      real(c_float), value :: value, opacity
      real(c_float) :: color(3)
      integer(c_int) :: c_style_add_isosurface
    end function
    function c_style_add_light(style, kind, direction, position, color, intensity) &
      bind(c, name="dfbwall_style_add_light")
      import :: c_ptr, c_int, c_float
      type(c_ptr), value :: style
      integer(c_int), value :: kind
      real(c_float) :: direction(3), position(3), color(3)
      real(c_float), value :: intensity
      integer(c_int) :: c_style_add_light
    end function
    function c_style_set_particles(style, color, opacity) bind(c, name="dfbwall_style_set_particles")
      import :: c_ptr, c_int, c_float
      type(c_ptr), value :: style
      real(c_float) :: color(3)
      real(c_float), value :: opacity
      integer(c_int) :: c_style_set_particles
    end function
    function c_style_set_mesh(style, color, opacity) bind(c, name="dfbwall_style_set_mesh")
      import :: c_ptr, c_int, c_float
      type(c_ptr), value :: style
      real(c_float) :: color(3)
      real(c_float), value :: opacity
      integer(c_int) :: c_style_set_mesh
    end function
    function c_style_set_ambient_occlusion(style, samples, distance) &
      bind(c, name="dfbwall_style_set_ambient_occlusion")
      import :: c_ptr, c_int, c_float
      type(c_ptr), value :: style
      integer(c_int), value :: samples
      real(c_float), value :: distance
      integer(c_int) :: c_style_set_ambient_occlusion
    end function
    function c_style_set_shadows(style, on) bind(c, name="dfbwall_style_set_shadows")
      import :: c_ptr, c_int
      type(c_ptr), value :: style
      integer(c_int), value :: on
      integer(c_int) :: c_style_set_shadows
    end function
    function c_style_set_sampling_rate(style, rate) bind(c, name="dfbwall_style_set_sampling_rate")
      import :: c_ptr, c_int, c_float
      type(c_ptr), value :: style
      real(c_float), value :: rate
      integer(c_int) :: c_style_set_sampling_rate
    end function
    function c_style_set_background(style, color) bind(c, name="dfbwall_style_set_background")
      import :: c_ptr, c_int, c_float
      type(c_ptr), value :: style
      real(c_float) :: color(3)
      integer(c_int) :: c_style_set_background
    end function
    function c_style_set_samples_per_pixel(style, spp) &
      bind(c, name="dfbwall_style_set_samples_per_pixel")
      import :: c_ptr, c_int
      type(c_ptr), value :: style
      integer(c_int), value :: spp
      integer(c_int) :: c_style_set_samples_per_pixel
    end function
    function c_style_set_seed(style, seed) bind(c, name="dfbwall_style_set_seed")
      import :: c_ptr, c_int, c_int64_t
      type(c_ptr), value :: style
      integer(c_int64_t), value :: seed
      integer(c_int) :: c_style_set_seed
    end function
    function c_session_new_f(comm, options, out) bind(c, name="dfbwall_session_new_f")
      import :: c_ptr, c_int
      integer(c_int), value :: comm
      type(c_ptr), value :: options
      type(c_ptr) :: out
      integer(c_int) :: c_session_new_f
    end function
    subroutine c_session_release(session) bind(c, name="dfbwall_session_release")
      import :: c_ptr
      type(c_ptr), value :: session
    end subroutine
    function c_session_is_wall_rank(session) bind(c, name="dfbwall_session_is_wall_rank")
      import :: c_ptr, c_int
      type(c_ptr), value :: session
      integer(c_int) :: c_session_is_wall_rank
    end function
    function c_session_render_comm_f(session) bind(c, name="dfbwall_session_render_comm_f")
      import :: c_ptr, c_int
      type(c_ptr), value :: session
      integer(c_int) :: c_session_render_comm_f
    end function
    function c_session_canvas_width(session) bind(c, name="dfbwall_session_canvas_width")
      import :: c_ptr, c_int
      type(c_ptr), value :: session
      integer(c_int) :: c_session_canvas_width
    end function
    function c_session_canvas_height(session) bind(c, name="dfbwall_session_canvas_height")
      import :: c_ptr, c_int
      type(c_ptr), value :: session
      integer(c_int) :: c_session_canvas_height
    end function
    function c_session_run_wall(session) bind(c, name="dfbwall_session_run_wall")
      import :: c_ptr, c_int
      type(c_ptr), value :: session
      integer(c_int) :: c_session_run_wall
    end function
    function c_session_set_style(session, style) bind(c, name="dfbwall_session_set_style")
      import :: c_ptr, c_int
      type(c_ptr), value :: session, style
      integer(c_int) :: c_session_set_style
    end function
    function c_session_add_brick(session, brick) bind(c, name="dfbwall_session_add_brick")
      import :: c_ptr, c_int, brick_c
      type(c_ptr), value :: session
      type(brick_c) :: brick
      integer(c_int) :: c_session_add_brick
    end function
    function c_session_clear_bricks(session) bind(c, name="dfbwall_session_clear_bricks")
      import :: c_ptr, c_int
      type(c_ptr), value :: session
      integer(c_int) :: c_session_clear_bricks
    end function
    function c_session_refuse_input(session, why) bind(c, name="dfbwall_session_refuse_input")
      import :: c_ptr, c_int, c_char
      type(c_ptr), value :: session
      character(kind=c_char) :: why(*)
      integer(c_int) :: c_session_refuse_input
    end function
    function c_session_set_camera(session, position, look_at, up, fov_y) &
      bind(c, name="dfbwall_session_set_camera")
      import :: c_ptr, c_int, c_float
      type(c_ptr), value :: session
      real(c_float) :: position(3), look_at(3), up(3)
      real(c_float), value :: fov_y
      integer(c_int) :: c_session_set_camera
    end function
    function c_session_render_frame(session) bind(c, name="dfbwall_session_render_frame")
      import :: c_ptr, c_int
      type(c_ptr), value :: session
      integer(c_int) :: c_session_render_frame
    end function
    function c_session_frames_rendered(session) bind(c, name="dfbwall_session_frames_rendered")
      import :: c_ptr, c_int32_t
      type(c_ptr), value :: session
      integer(c_int32_t) :: c_session_frames_rendered
    end function
    function c_session_image(session, pixels, width, height) bind(c, name="dfbwall_session_image")
      import :: c_ptr, c_int
      type(c_ptr), value :: session
      type(c_ptr) :: pixels
      integer(c_int) :: width, height
      integer(c_int) :: c_session_image
    end function
    function c_session_write_image(session, path) bind(c, name="dfbwall_session_write_image")
      import :: c_ptr, c_int, c_char
      type(c_ptr), value :: session
      character(kind=c_char) :: path(*)
      integer(c_int) :: c_session_write_image
    end function
    function c_session_scene_bytes(session) bind(c, name="dfbwall_session_scene_bytes")
      import :: c_ptr, c_size_t
      type(c_ptr), value :: session
      integer(c_size_t) :: c_session_scene_bytes
    end function
    function c_session_close(session) bind(c, name="dfbwall_session_close")
      import :: c_ptr, c_int
      type(c_ptr), value :: session
      integer(c_int) :: c_session_close
    end function
  end interface

contains

  ! ---- Errors ----

  ! The outcome of a C call: into status when given; else a failure stops with its message.
  subroutine outcome(code, status)
    integer(c_int), intent(in) :: code
    integer, intent(out), optional :: status
    if (present(status)) then
      status = int(code)
      return
    end if
    if (code == DFBWALL_OK) return
    call stop_with(dfbwall_last_error())
  end subroutine

  subroutine stop_with(message)
    character(len=*), intent(in) :: message
    write (error_unit, '(a)') message
    flush (error_unit)
    error stop 1, quiet=.true.
  end subroutine

  ! The message of the last failed call ("" when none did).
  function dfbwall_last_error() result(message)
    character(len=:), allocatable :: message
    type(c_ptr) :: p
    character(kind=c_char), pointer :: chars(:)
    integer :: i, n
    p = c_last_error()
    n = 0
    if (c_associated(p)) n = int(c_strlen(p))
    allocate (character(len=n) :: message)
    if (n == 0) return
    call c_f_pointer(p, chars, [n])
    do i = 1, n
      message(i:i) = chars(i)
    end do
  end function

  integer function dfbwall_last_error_code()
    dfbwall_last_error_code = int(c_last_error_code())
  end function

  ! handler: c_funloc of a bind(c) subroutine (type(c_ptr), value :: user;
  ! integer(c_int), value :: code; type(c_ptr), value :: message), or c_null_funptr to remove it.
  subroutine dfbwall_set_error_function(handler, user)
    type(c_funptr), intent(in) :: handler
    type(c_ptr), intent(in), optional :: user
    if (present(user)) then
      call c_set_error_function(handler, user)
    else
      call c_set_error_function(handler, c_null_ptr)
    end if
  end subroutine

  ! Fortran text as a C string: trailing blanks dropped, as Fortran pads.
  pure function c_text(text) result(out)
    character(len=*), intent(in) :: text
    character(kind=c_char, len=len_trim(text) + 1) :: out
    out = trim(text)//c_null_char
  end function

  pure integer(c_int) function c_flag(flag)
    logical, intent(in) :: flag
    c_flag = merge(1_c_int, 0_c_int, flag)
  end function

  ! ---- Options ----

  subroutine dfbwall_options_new(options, status)
    type(dfbwall_options), intent(out) :: options
    integer, intent(out), optional :: status
    call outcome(c_options_new(options%ptr), status)
  end subroutine

  ! key and value as dfbwall.h names them ("wall", "connect", "width", ...).
  subroutine dfbwall_options_set(options, key, value, status)
    type(dfbwall_options), intent(in) :: options
    character(len=*), intent(in) :: key, value
    integer, intent(out), optional :: status
    call outcome(c_options_set(options%ptr, c_text(key), c_text(value)), status)
  end subroutine

  subroutine dfbwall_options_release(options)
    type(dfbwall_options), intent(inout) :: options
    call c_options_release(options%ptr)
    options%ptr = c_null_ptr
  end subroutine

  ! ---- Style ----

  subroutine dfbwall_style_new(style, status)
    type(dfbwall_style), intent(out) :: style
    integer, intent(out), optional :: status
    call outcome(c_style_new(style%ptr), status)
  end subroutine

  subroutine dfbwall_style_release(style)
    type(dfbwall_style), intent(inout) :: style
    call c_style_release(style%ptr)
    style%ptr = c_null_ptr
  end subroutine

  ! Volumes are numbered from 0 as in C: index is the number the other calls take.
  subroutine dfbwall_style_add_volume(style, name, dims, origin, spacing, index, status)
    type(dfbwall_style), intent(in) :: style
    character(len=*), intent(in) :: name
    integer, intent(in) :: dims(3)
    real(c_float), intent(in) :: origin(3), spacing(3)
    integer, intent(out), optional :: index
    integer, intent(out), optional :: status
    integer(c_int) :: c_dims(3), c_index
    real(c_float) :: c_origin(3), c_spacing(3)
    c_dims = int(dims, c_int)
    c_origin = origin
    c_spacing = spacing
    c_index = -1
    call outcome(c_style_add_volume(style%ptr, c_text(name), c_dims, c_origin, c_spacing, &
                                    c_index), status)
    if (present(index)) index = int(c_index)
  end subroutine

  subroutine dfbwall_style_set_transfer_function(style, volume, preset, max_opacity, status)
    type(dfbwall_style), intent(in) :: style
    integer, intent(in) :: volume
    character(len=*), intent(in) :: preset
    real(c_float), intent(in) :: max_opacity
    integer, intent(out), optional :: status
    call outcome(c_style_set_transfer_function(style%ptr, int(volume, c_int), c_text(preset), &
                                               max_opacity), status)
  end subroutine

  subroutine dfbwall_style_set_value_range(style, volume, min, max, status)
    type(dfbwall_style), intent(in) :: style
    integer, intent(in) :: volume
    real(c_float), intent(in) :: min, max
    integer, intent(out), optional :: status
    call outcome(c_style_set_value_range(style%ptr, int(volume, c_int), min, max), status)
  end subroutine

  subroutine dfbwall_style_set_volume_visible(style, volume, visible, status)
    type(dfbwall_style), intent(in) :: style
    integer, intent(in) :: volume
    logical, intent(in) :: visible
    integer, intent(out), optional :: status
    call outcome(c_style_set_volume_visible(style%ptr, int(volume, c_int), c_flag(visible)), &
                 status)
  end subroutine

  subroutine dfbwall_style_add_isosurface(style, volume, value, color, opacity, status)
    type(dfbwall_style), intent(in) :: style
    integer, intent(in) :: volume
    real(c_float), intent(in) :: value, color(3), opacity
    integer, intent(out), optional :: status
    real(c_float) :: c_color(3)
    c_color = color
    call outcome(c_style_add_isosurface(style%ptr, int(volume, c_int), value, c_color, opacity), &
                 status)
  end subroutine

  ! kind: DFBWALL_LIGHT_*; direction: the way the light travels.
  subroutine dfbwall_style_add_light(style, kind, direction, position, color, intensity, status)
    type(dfbwall_style), intent(in) :: style
    integer, intent(in) :: kind
    real(c_float), intent(in) :: direction(3), position(3), color(3), intensity
    integer, intent(out), optional :: status
    real(c_float) :: d(3), p(3), c(3)
    d = direction
    p = position
    c = color
    call outcome(c_style_add_light(style%ptr, int(kind, c_int), d, p, c, intensity), status)
  end subroutine

  subroutine dfbwall_style_set_particles(style, color, opacity, status)
    type(dfbwall_style), intent(in) :: style
    real(c_float), intent(in) :: color(3), opacity
    integer, intent(out), optional :: status
    real(c_float) :: c(3)
    c = color
    call outcome(c_style_set_particles(style%ptr, c, opacity), status)
  end subroutine

  subroutine dfbwall_style_set_mesh(style, color, opacity, status)
    type(dfbwall_style), intent(in) :: style
    real(c_float), intent(in) :: color(3), opacity
    integer, intent(out), optional :: status
    real(c_float) :: c(3)
    c = color
    call outcome(c_style_set_mesh(style%ptr, c, opacity), status)
  end subroutine

  subroutine dfbwall_style_set_ambient_occlusion(style, samples, distance, status)
    type(dfbwall_style), intent(in) :: style
    integer, intent(in) :: samples
    real(c_float), intent(in) :: distance
    integer, intent(out), optional :: status
    call outcome(c_style_set_ambient_occlusion(style%ptr, int(samples, c_int), distance), status)
  end subroutine

  subroutine dfbwall_style_set_shadows(style, on, status)
    type(dfbwall_style), intent(in) :: style
    logical, intent(in) :: on
    integer, intent(out), optional :: status
    call outcome(c_style_set_shadows(style%ptr, c_flag(on)), status)
  end subroutine

  subroutine dfbwall_style_set_sampling_rate(style, rate, status)
    type(dfbwall_style), intent(in) :: style
    real(c_float), intent(in) :: rate
    integer, intent(out), optional :: status
    call outcome(c_style_set_sampling_rate(style%ptr, rate), status)
  end subroutine

  subroutine dfbwall_style_set_background(style, color, status)
    type(dfbwall_style), intent(in) :: style
    real(c_float), intent(in) :: color(3)
    integer, intent(out), optional :: status
    real(c_float) :: c(3)
    c = color
    call outcome(c_style_set_background(style%ptr, c), status)
  end subroutine

  subroutine dfbwall_style_set_samples_per_pixel(style, spp, status)
    type(dfbwall_style), intent(in) :: style
    integer, intent(in) :: spp
    integer, intent(out), optional :: status
    call outcome(c_style_set_samples_per_pixel(style%ptr, int(spp, c_int)), status)
  end subroutine

  subroutine dfbwall_style_set_seed(style, seed, status)
    type(dfbwall_style), intent(in) :: style
    integer(c_int64_t), intent(in) :: seed
    integer, intent(out), optional :: status
    call outcome(c_style_set_seed(style%ptr, seed), status)
  end subroutine

  ! ---- Bricks ----

  ! A brick with nothing in it yet: id >= 0 (the same id on two ranks: the same data); camera
  ! rays are clipped to [bounds_lo, bounds_hi]. exchange_ghosts=.true.: each volume part is the
  ! box the brick owns and the session exchanges the ghost voxels its renderer reads
  ! (DFBWALL_GHOSTS_EXCHANGE); otherwise the parts carry them.
  subroutine dfbwall_brick_init(brick, id, bounds_lo, bounds_hi, exchange_ghosts)
    type(dfbwall_brick), intent(out) :: brick
    integer, intent(in) :: id
    real(c_float), intent(in) :: bounds_lo(3), bounds_hi(3)
    logical, intent(in), optional :: exchange_ghosts
    integer(c_int) :: ghosts
    ghosts = DFBWALL_GHOSTS_GIVEN
    if (present(exchange_ghosts)) then
      if (exchange_ghosts) ghosts = DFBWALL_GHOSTS_EXCHANGE
    end if
    brick%c = brick_c(int(id, c_int), bounds_lo, bounds_hi, c_null_ptr, 0, c_null_ptr, 0, &
                      c_null_ptr, 0, c_null_ptr, 0, c_null_ptr, 0, c_null_ptr, 0, c_null_ptr, 0, &
                      c_null_ptr, 0, c_null_ptr, 0, ghosts)
    allocate (brick%parts(4))
    brick%part_count = 0
    brick%ready = .true.
  end subroutine

  ! The next style volume's part: a part (lo, hi) of the field at voxels, or none (lo == hi).
  subroutine add_part(brick, lo, extent, voxel_type, voxels, contiguous)
    type(dfbwall_brick), intent(inout) :: brick
    integer, intent(in) :: lo(3), extent(3)
    integer(c_int), intent(in) :: voxel_type
    type(c_ptr), intent(in) :: voxels
    logical, intent(in) :: contiguous
    type(volume_part_c), allocatable :: grown(:)
    character(len=32) :: number
    if (.not. allocated(brick%parts)) allocate (brick%parts(4))
    if (brick%part_count == size(brick%parts)) then
      allocate (grown(2*size(brick%parts)))
      grown(1:brick%part_count) = brick%parts(1:brick%part_count)
      call move_alloc(grown, brick%parts)
    end if
    brick%part_count = brick%part_count + 1
    brick%parts(brick%part_count) = volume_part_c(int(lo, c_int), int(lo + extent, c_int), &
                                                  voxel_type, voxels)
    if (.not. contiguous .and. .not. allocated(brick%problem)) then
      write (number, '(i0)') brick%part_count - 1
      brick%problem = "volume part "//trim(number)//": the array is not contiguous "// &
                      "(give a whole array or a section of whole leading dimensions)"
    end if
  end subroutine

  ! lo: the whole-field voxel (0-based, x y z) of voxels' first element.
  subroutine add_volume_real4(brick, lo, voxels)
    type(dfbwall_brick), intent(inout) :: brick
    integer, intent(in) :: lo(3)
    real(c_float), intent(in), target :: voxels(:, :, :)
    call add_part(brick, lo, shape(voxels), FLOAT32, address(), is_contiguous(voxels))
  contains
    type(c_ptr) function address()
      address = c_null_ptr
      if (is_contiguous(voxels) .and. size(voxels) > 0) address = c_loc(voxels)
    end function
  end subroutine

  subroutine add_volume_real8(brick, lo, voxels)
    type(dfbwall_brick), intent(inout) :: brick
    integer, intent(in) :: lo(3)
    real(c_double), intent(in), target :: voxels(:, :, :)
    call add_part(brick, lo, shape(voxels), FLOAT64, address(), is_contiguous(voxels))
  contains
    type(c_ptr) function address()
      address = c_null_ptr
      if (is_contiguous(voxels) .and. size(voxels) > 0) address = c_loc(voxels)
    end function
  end subroutine

  ! unsigned: the bits are uint8 (Fortran has no unsigned kinds); else int8.
  subroutine add_volume_int1(brick, lo, voxels, unsigned)
    type(dfbwall_brick), intent(inout) :: brick
    integer, intent(in) :: lo(3)
    integer(c_int8_t), intent(in), target :: voxels(:, :, :)
    logical, intent(in), optional :: unsigned
    integer(c_int) :: voxel_type
    voxel_type = INT8
    if (present(unsigned)) then
      if (unsigned) voxel_type = UINT8
    end if
    call add_part(brick, lo, shape(voxels), voxel_type, address(), is_contiguous(voxels))
  contains
    type(c_ptr) function address()
      address = c_null_ptr
      if (is_contiguous(voxels) .and. size(voxels) > 0) address = c_loc(voxels)
    end function
  end subroutine

  ! unsigned: the bits are uint16; else int16.
  subroutine add_volume_int2(brick, lo, voxels, unsigned)
    type(dfbwall_brick), intent(inout) :: brick
    integer, intent(in) :: lo(3)
    integer(c_int16_t), intent(in), target :: voxels(:, :, :)
    logical, intent(in), optional :: unsigned
    integer(c_int) :: voxel_type
    voxel_type = INT16
    if (present(unsigned)) then
      if (unsigned) voxel_type = UINT16
    end if
    call add_part(brick, lo, shape(voxels), voxel_type, address(), is_contiguous(voxels))
  contains
    type(c_ptr) function address()
      address = c_null_ptr
      if (is_contiguous(voxels) .and. size(voxels) > 0) address = c_loc(voxels)
    end function
  end subroutine

  subroutine add_volume_int4(brick, lo, voxels)
    type(dfbwall_brick), intent(inout) :: brick
    integer, intent(in) :: lo(3)
    integer(c_int32_t), intent(in), target :: voxels(:, :, :)
    call add_part(brick, lo, shape(voxels), INT32, address(), is_contiguous(voxels))
  contains
    type(c_ptr) function address()
      address = c_null_ptr
      if (is_contiguous(voxels) .and. size(voxels) > 0) address = c_loc(voxels)
    end function
  end subroutine

  ! This brick holds none of the next style volume.
  subroutine dfbwall_brick_add_no_volume(brick)
    type(dfbwall_brick), intent(inout) :: brick
    call add_part(brick, [0, 0, 0], [0, 0, 0], FLOAT32, c_null_ptr, .true.)
  end subroutine

  ! centers(3, n); radii(1) for all particles or radii(n).
  subroutine dfbwall_brick_set_particles(brick, centers, radii)
    type(dfbwall_brick), intent(inout) :: brick
    real(c_float), intent(in), target :: centers(:, :), radii(:)
    call check_points(brick, "particle centers", centers)
    call check_array(brick, "particle radii", is_contiguous(radii))
    brick%c%particle_centers = first(centers)
    brick%c%particle_count = size(centers, 2, c_size_t)
    brick%c%particle_radii = first1(radii)
    brick%c%radius_count = size(radii, kind=c_size_t)
  end subroutine

  ! Seen by shading rays only.
  subroutine dfbwall_brick_set_ghost_particles(brick, centers, radii)
    type(dfbwall_brick), intent(inout) :: brick
    real(c_float), intent(in), target :: centers(:, :), radii(:)
    call check_points(brick, "ghost particle centers", centers)
    call check_array(brick, "ghost particle radii", is_contiguous(radii))
    brick%c%ghost_particle_centers = first(centers)
    brick%c%ghost_particle_count = size(centers, 2, c_size_t)
    brick%c%ghost_particle_radii = first1(radii)
    brick%c%ghost_radius_count = size(radii, kind=c_size_t)
  end subroutine

  ! positions(3, n); triangles(3, m): 0-based indices into positions, as in C.
  subroutine dfbwall_brick_set_mesh(brick, positions, triangles)
    type(dfbwall_brick), intent(inout) :: brick
    real(c_float), intent(in), target :: positions(:, :)
    integer(c_int32_t), intent(in), target :: triangles(:, :)
    call check_points(brick, "mesh positions", positions)
    call check_triangles(brick, "mesh triangles", triangles)
    brick%c%mesh_positions = first(positions)
    brick%c%mesh_position_count = size(positions, 2, c_size_t)
    brick%c%mesh_triangles = first_index(triangles)
    brick%c%mesh_triangle_count = size(triangles, 2, c_size_t)
  end subroutine

  ! Seen by shading rays only.
  subroutine dfbwall_brick_set_ghost_mesh(brick, positions, triangles)
    type(dfbwall_brick), intent(inout) :: brick
    real(c_float), intent(in), target :: positions(:, :)
    integer(c_int32_t), intent(in), target :: triangles(:, :)
    call check_points(brick, "ghost mesh positions", positions)
    call check_triangles(brick, "ghost mesh triangles", triangles)
    brick%c%ghost_mesh_positions = first(positions)
    brick%c%ghost_mesh_position_count = size(positions, 2, c_size_t)
    brick%c%ghost_mesh_triangles = first_index(triangles)
    brick%c%ghost_mesh_triangle_count = size(triangles, 2, c_size_t)
  end subroutine

  subroutine check_array(brick, what, contiguous)
    type(dfbwall_brick), intent(inout) :: brick
    character(len=*), intent(in) :: what
    logical, intent(in) :: contiguous
    if (.not. contiguous .and. .not. allocated(brick%problem)) &
      brick%problem = what//": the array is not contiguous"
  end subroutine

  subroutine check_points(brick, what, points)
    type(dfbwall_brick), intent(inout) :: brick
    character(len=*), intent(in) :: what
    real(c_float), intent(in) :: points(:, :)
    character(len=32) :: rows
    call check_array(brick, what, is_contiguous(points))
    if (size(points, 1) /= 3 .and. .not. allocated(brick%problem)) then
      write (rows, '(i0)') size(points, 1)
      brick%problem = what//": the array has "//trim(rows)//" rows, not 3 (x, y, z)"
    end if
  end subroutine

  subroutine check_triangles(brick, what, triangles)
    type(dfbwall_brick), intent(inout) :: brick
    character(len=*), intent(in) :: what
    integer(c_int32_t), intent(in) :: triangles(:, :)
    character(len=32) :: rows
    call check_array(brick, what, is_contiguous(triangles))
    if (size(triangles, 1) /= 3 .and. .not. allocated(brick%problem)) then
      write (rows, '(i0)') size(triangles, 1)
      brick%problem = what//": the array has "//trim(rows)//" rows, not 3 indices"
    end if
  end subroutine

  type(c_ptr) function first(a)
    real(c_float), intent(in), target :: a(:, :)
    first = c_null_ptr
    if (size(a) > 0 .and. is_contiguous(a)) first = c_loc(a)
  end function

  type(c_ptr) function first1(a)
    real(c_float), intent(in), target :: a(:)
    first1 = c_null_ptr
    if (size(a) > 0 .and. is_contiguous(a)) first1 = c_loc(a)
  end function

  type(c_ptr) function first_index(a)
    integer(c_int32_t), intent(in), target :: a(:, :)
    first_index = c_null_ptr
    if (size(a) > 0 .and. is_contiguous(a)) first_index = c_loc(a)
  end function

  ! ---- Session ----

  ! Collective over comm (an MPI integer handle: the `mpi` module's, or mpi_f08's comm%MPI_VAL).
  ! Without options: an 800x600 image.
  subroutine dfbwall_session_new(session, comm, options, status)
    type(dfbwall_session), intent(out) :: session
    integer, intent(in) :: comm
    type(dfbwall_options), intent(in), optional :: options
    integer, intent(out), optional :: status
    type(c_ptr) :: o
    o = c_null_ptr
    if (present(options)) o = options%ptr
    call outcome(c_session_new_f(int(comm, c_int), o, session%ptr), status)
  end subroutine

  ! Not collective: without dfbwall_session_close before, the session leaves (the other ranks
  ! fail at once, naming this one).
  subroutine dfbwall_session_release(session)
    type(dfbwall_session), intent(inout) :: session
    call c_session_release(session%ptr)
    session%ptr = c_null_ptr
  end subroutine

  logical function dfbwall_session_is_wall_rank(session)
    type(dfbwall_session), intent(in) :: session
    dfbwall_session_is_wall_rank = c_session_is_wall_rank(session%ptr) /= 0
  end function

  ! The render ranks' communicator as an MPI integer handle (MPI_COMM_NULL's on wall ranks).
  integer function dfbwall_session_render_comm(session)
    type(dfbwall_session), intent(in) :: session
    dfbwall_session_render_comm = int(c_session_render_comm_f(session%ptr))
  end function

  integer function dfbwall_session_canvas_width(session)
    type(dfbwall_session), intent(in) :: session
    dfbwall_session_canvas_width = int(c_session_canvas_width(session%ptr))
  end function

  integer function dfbwall_session_canvas_height(session)
    type(dfbwall_session), intent(in) :: session
    dfbwall_session_canvas_height = int(c_session_canvas_height(session%ptr))
  end function

  subroutine dfbwall_session_run_wall(session, status)
    type(dfbwall_session), intent(in) :: session
    integer, intent(out), optional :: status
    call outcome(c_session_run_wall(session%ptr), status)
  end subroutine

  subroutine dfbwall_session_set_style(session, style, status)
    type(dfbwall_session), intent(in) :: session
    type(dfbwall_style), intent(in) :: style
    integer, intent(out), optional :: status
    call outcome(c_session_set_style(session%ptr, style%ptr), status)
  end subroutine

  ! Reads the brick's arrays. An array this module cannot pass (not contiguous, not 3 rows), or a
  ! brick not made by dfbwall_brick_init, is refused like a brick that does not fit: by the next
  ! render_frame, on every render rank.
  subroutine dfbwall_session_add_brick(session, brick, status)
    type(dfbwall_session), intent(in) :: session
    type(dfbwall_brick), intent(inout), target :: brick
    integer, intent(out), optional :: status
    character(len=32) :: id
    if (.not. brick%ready) then
      call outcome(c_session_refuse_input(session%ptr, &
                                          c_text("dfbwall: a brick before dfbwall_brick_init")), &
                   status)
      return
    end if
    if (allocated(brick%problem)) then
      write (id, '(i0)') brick%c%id
      call outcome(c_session_refuse_input(session%ptr, c_text("dfbwall: brick "//trim(id)// &
                                                              ": "//brick%problem)), status)
      return
    end if
    brick%c%volume_count = int(brick%part_count, c_size_t)
    brick%c%volumes = c_null_ptr
    if (brick%part_count > 0) brick%c%volumes = c_loc(brick%parts(1))
    call outcome(c_session_add_brick(session%ptr, brick%c), status)
  end subroutine

  subroutine dfbwall_session_clear_bricks(session, status)
    type(dfbwall_session), intent(in) :: session
    integer, intent(out), optional :: status
    call outcome(c_session_clear_bricks(session%ptr), status)
  end subroutine

  ! Render rank 0's camera is the one used. fov_y in degrees.
  subroutine dfbwall_session_set_camera(session, position, look_at, up, fov_y, status)
    type(dfbwall_session), intent(in) :: session
    real(c_float), intent(in) :: position(3), look_at(3), up(3), fov_y
    integer, intent(out), optional :: status
    real(c_float) :: p(3), l(3), u(3)
    p = position
    l = look_at
    u = up
    call outcome(c_session_set_camera(session%ptr, p, l, u, fov_y), status)
  end subroutine

  subroutine dfbwall_session_render_frame(session, status)
    type(dfbwall_session), intent(in) :: session
    integer, intent(out), optional :: status
    call outcome(c_session_render_frame(session%ptr), status)
  end subroutine

  integer function dfbwall_session_frames_rendered(session)
    type(dfbwall_session), intent(in) :: session
    dfbwall_session_frames_rendered = int(c_session_frames_rendered(session%ptr))
  end function

  ! Render rank 0 without a wall: the last frame as pixels(4, width, height), RGBA8 bytes, row 1
  ! the top, valid until the session's next call; elsewhere pixels is null and the size 0.
  subroutine dfbwall_session_image(session, pixels, width, height, status)
    type(dfbwall_session), intent(in) :: session
    integer(c_int8_t), pointer, intent(out) :: pixels(:, :, :)
    integer, intent(out) :: width, height
    integer, intent(out), optional :: status
    type(c_ptr) :: p
    integer(c_int) :: w, h, code
    p = c_null_ptr
    w = 0
    h = 0
    pixels => null()
    code = c_session_image(session%ptr, p, w, h)
    width = int(w)
    height = int(h)
    if (code == DFBWALL_OK .and. c_associated(p)) call c_f_pointer(p, pixels, [4, width, height])
    call outcome(code, status)
  end subroutine

  ! Render rank 0 without a wall: the last frame as a PNG; elsewhere nothing.
  subroutine dfbwall_session_write_image(session, path, status)
    type(dfbwall_session), intent(in) :: session
    character(len=*), intent(in) :: path
    integer, intent(out), optional :: status
    call outcome(c_session_write_image(session%ptr, c_text(path)), status)
  end subroutine

  ! The bytes of brick data this rank holds in the current scene version.
  integer(c_size_t) function dfbwall_session_scene_bytes(session)
    type(dfbwall_session), intent(in) :: session
    dfbwall_session_scene_bytes = c_session_scene_bytes(session%ptr)
  end function

  ! Render ranks, collective with run_wall returning on the wall ranks.
  subroutine dfbwall_session_close(session, status)
    type(dfbwall_session), intent(in) :: session
    integer, intent(out), optional :: status
    call outcome(c_session_close(session%ptr), status)
  end subroutine

end module dfbwall
