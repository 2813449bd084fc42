from setuptools import find_packages, setup

package_name = 'hrc_partners'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='hrc developers',
    maintainer_email='hrc@example.org',
    description='Human models cloned from recordings, cross-play, role allocation advisor.',
    license='Apache-2.0',
    entry_points={
        # its commands are verbs of `hrc` (hrc_bringup/cli.py)
        'console_scripts': [],
    },
)
